/// @file TestCellBandTerms.cc
/// @brief CellBandTerms (the band terms of the symmetric energy for the band simplices of a
///        cell, lane by lane) computes the same bits as the per-simplex code it replaces in the
///        energy loop: kinematics::makeFrame, the direct and inverse match, membrane and bending
///        densities (eq:EsymMatch, eq:EsymMem, eq:EsymBend) with their derivatives, and
///        kinematics::frameAdjoint. Each lane must repeat Eigen's evaluation order; a reordered
///        sum fails here on most inputs.
#include "support/RandomMatrices.h"
#include "support/SameBits.h"

#include <vdbmatch/energy/BendingTerm.h>
#include <vdbmatch/energy/CellBandTerms.h>
#include <vdbmatch/energy/MatchTerm.h>
#include <vdbmatch/energy/MembraneTerm.h>

#include <gtest/gtest.h>

#include <array>

using namespace vdbmatch;
using namespace vdbmatch::energy;
using vdbmatch::test::sameBits;

namespace {

template <int D>
void
expectSame(const Mat<D>& m, const Real (&lanes)[D][D][CellBandTerms<D>::N], int q, const char* what,
           int trial)
{
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            ASSERT_TRUE(sameBits(m(i, j), lanes[i][j][q]))
                << what << "(" << i << "," << j << "), trial " << trial << " lane " << q << ": "
                << m(i, j) << " vs " << lanes[i][j][q];
}

template <int D>
void
expectSame(const Vec<D>& v, const Real (&lanes)[D][CellBandTerms<D>::N], int q, const char* what,
           int trial)
{
    for (int i = 0; i < D; ++i)
        ASSERT_TRUE(sameBits(v[i], lanes[i][q]))
            << what << "[" << i << "], trial " << trial << " lane " << q;
}

/// Raw fields of a shape at a point: d, a normal near unit length, R = S^{1/2} symmetric
/// positive definite; and random derivatives.
template <int D>
void
randomRaw(test::RandomSource& random, RawFields<D>& raw, RawFieldDerivatives<D>& deriv)
{
    raw.d = random.uniform(-0.02, 0.02);
    raw.n = random.template unitVector<D>() * random.uniform(0.8, 1.2);
    raw.R = random.template spd<D>(0.5, 2.0);
    deriv.dd = random.template matrix<D>(1.0).col(0);
    deriv.dn = random.template matrix<D>(3.0);
    for (int k = 0; k < D; ++k)
        deriv.dR[k] = random.template matrix<D>(5.0);
}

template <int D>
void
checkAgainstPerSimplexCode(unsigned seed, Real memSaturation = 0)
{
    constexpr int N = CellBandTerms<D>::N;
    test::RandomSource random(seed);
    const Real cMatch = 4.096 * 1e3, cMem = 3.0, cBend = 0.2;
    int lanesChecked = 0, directOff = 0, inverseOff = 0, saturatedLanes = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        CellBandTerms<D> band, values;
        band.count = 1 + trial % N;
        struct Lane
        {
            SimplexKinematics<D> k;
            PointGeometry<D> g;
            RawFields<D> raw2;
            RawFieldDerivatives<D> deriv2;
            Mat<D> dA0, dB0;
        };
        std::array<Lane, N> lane;
        for (int q = 0; q < band.count; ++q) {
            Lane& L = lane[q];
            const int kind = (trial + q) % 3;
            const Mat<D> A =
                kind == 0 ? random.template positiveMatrix<D>(0.3)
                : kind == 1
                    ? Mat<D>(random.template rotation<D>() * random.template positiveMatrix<D>(0.6))
                    : Mat<D>(Mat<D>::Identity() + random.template matrix<D>(0.05));
            L.k = SimplexKinematics<D>(A);
            if (!(L.k.J > 0)) L.k = SimplexKinematics<D>(Mat<D>::Identity());
            RawFields<D> raw1;
            RawFieldDerivatives<D> unused;
            randomRaw<D>(random, raw1, unused);
            kinematics::makeFrame(raw1, L.g.f1);
            randomRaw<D>(random, L.raw2, L.deriv2);
            // Both halves, or one of them only (the other's weight 0).
            const int halves = (trial / N + q) % 4;
            L.g.eta1 = halves == 1 ? 0.0 : random.uniform(0.0, 40.0);
            L.g.eta2 = halves == 2 ? 0.0 : random.uniform(0.0, 40.0);
            L.g.eta2Derivative = L.g.eta2 > 0 ? random.uniform(-900.0, 900.0) : 0.0;
            directOff += L.g.eta1 > 0 ? 0 : 1;
            inverseOff += L.g.eta2 > 0 ? 0 : 1;
            L.dA0 = random.template matrix<D>(1.0);
            L.dB0 = random.template matrix<D>(1.0);
            for (int i = 0; i < D; ++i) {
                band.n1[i][q] = L.g.f1.n[i];
                band.rawN2[i][q] = L.raw2.n[i];
                band.dd2[i][q] = L.deriv2.dd[i];
                for (int j = 0; j < D; ++j) {
                    band.A[i][j][q] = L.k.A(i, j);
                    band.C[i][j][q] = L.k.C(i, j);
                    band.B[i][j][q] = L.k.B(i, j);
                    band.dA[i][j][q] = L.dA0(i, j);
                    band.dB[i][j][q] = L.dB0(i, j);
                    band.P1[i][j][q] = L.g.f1.P(i, j);
                    band.Tp1[i][j][q] = L.g.f1.Tp(i, j);
                    band.Tm1[i][j][q] = L.g.f1.Tm(i, j);
                    band.R2[i][j][q] = L.raw2.R(i, j);
                    band.dn2[i][j][q] = L.deriv2.dn(i, j);
                    for (int k = 0; k < D; ++k)
                        band.dR2[k][i][j][q] = L.deriv2.dR[k](i, j);
                }
            }
            band.J[q] = L.k.J;
            band.eta1[q] = L.g.eta1;
            band.eta2[q] = L.g.eta2;
            band.eta2D[q] = L.g.eta2Derivative;
            band.d1[q] = L.g.f1.d;
            band.d2[q] = L.raw2.d;
        }
        values = band;
        band.frame();
        band.template terms<true>(cMatch, cMem, cBend, true, memSaturation);
        band.adjoint();
        values.frame();
        values.template terms<false>(cMatch, cMem, cBend, true, memSaturation);

        for (int q = 0; q < band.count; ++q) {
            Lane& L = lane[q];
            kinematics::makeFrame(L.raw2, L.g.f2);
            ASSERT_TRUE(sameBits(L.g.f2.nLength, band.nLength2[q])) << "|n|, trial " << trial;
            expectSame<D>(L.g.f2.n, band.n2, q, "n2", trial);
            expectSame<D>(L.g.f2.P, band.P2, q, "P2", trial);
            expectSame<D>(L.g.f2.Tp, band.Tp2, q, "Tp2", trial);
            expectSame<D>(L.g.f2.Minv, band.Minv2, q, "Minv2", trial);
            expectSame<D>(L.g.f2.Tm, band.Tm2, q, "Tm2", trial);

            // The per-simplex code, as in the energy loop before the lanes.
            DensityGradient<D> dg;
            dg.dA = L.dA0;
            dg.dB = L.dB0;
            Real e[6] = {0, 0, 0, 0, 0, 0};
            Real v[6] = {0, 0, 0, 0, 0, 0};
            if (L.g.eta1 > 0) {
                e[0] = matchDirect<D, true>(L.g, cMatch, &dg);
                e[1] = membraneDirect<D, true>(L.k, L.g, cMem, memSaturation, &dg);
                e[2] = bendingDirect<D, true>(L.k, L.g, cBend, &dg);
                v[0] = matchDirect<D, false>(L.g, cMatch, nullptr);
                v[1] = membraneDirect<D, false>(L.k, L.g, cMem, memSaturation, nullptr);
                if (v[1] < membraneDirect<D, false>(L.k, L.g, cMem, 0.0, nullptr)) ++saturatedLanes;
                v[2] = bendingDirect<D, false>(L.k, L.g, cBend, nullptr);
                ASSERT_TRUE(sameBits(e[0], band.matchDirect[q])) << "match direct " << trial;
                ASSERT_TRUE(sameBits(e[1], band.memDirect[q])) << "membrane direct " << trial;
                ASSERT_TRUE(sameBits(e[2], band.bendDirect[q])) << "bending direct " << trial;
                ASSERT_TRUE(sameBits(v[0], values.matchDirect[q]));
                ASSERT_TRUE(sameBits(v[1], values.memDirect[q]));
                ASSERT_TRUE(sameBits(v[2], values.bendDirect[q]));
            }
            if (L.g.eta2 > 0) {
                e[3] = matchInverse<D, true>(L.k, L.g, cMatch, &dg);
                e[4] = membraneInverse<D, true>(L.k, L.g, cMem, memSaturation, &dg);
                e[5] = bendingInverse<D, true>(L.k, L.g, cBend, &dg);
                v[3] = matchInverse<D, false>(L.k, L.g, cMatch, nullptr);
                v[4] = membraneInverse<D, false>(L.k, L.g, cMem, memSaturation, nullptr);
                v[5] = bendingInverse<D, false>(L.k, L.g, cBend, nullptr);
                ASSERT_TRUE(sameBits(e[3], band.matchInverse[q])) << "match inverse " << trial;
                ASSERT_TRUE(sameBits(e[4], band.memInverse[q])) << "membrane inverse " << trial;
                ASSERT_TRUE(sameBits(e[5], band.bendInverse[q])) << "bending inverse " << trial;
                ASSERT_TRUE(sameBits(v[3], values.matchInverse[q]));
                ASSERT_TRUE(sameBits(v[4], values.memInverse[q]));
                ASSERT_TRUE(sameBits(v[5], values.bendInverse[q]));
            }
            expectSame<D>(dg.dA, band.dA, q, "dA", trial);
            expectSame<D>(dg.dB, band.dB, q, "dB", trial);
            ASSERT_TRUE(sameBits(dg.f2.d, band.ad[q])) << "adjoint d, trial " << trial;
            expectSame<D>(dg.f2.n, band.an, q, "adjoint n", trial);
            expectSame<D>(dg.f2.P, band.aP, q, "adjoint P", trial);
            expectSame<D>(dg.f2.Tp, band.aTp, q, "adjoint Tp", trial);
            expectSame<D>(dg.f2.Tm, band.aTm, q, "adjoint Tm", trial);
            const Vec<D> dy = kinematics::frameAdjoint(L.raw2, L.deriv2, L.g.f2, dg.f2);
            expectSame<D>(dy, band.dy, q, "dE/dy", trial);
            ++lanesChecked;
        }
    }
    EXPECT_GT(lanesChecked, 4000);
    EXPECT_GT(directOff, 500); // lanes with one half off were exercised
    EXPECT_GT(inverseOff, 500);
    // With a saturation, it lowered the membrane density of most lanes (W > 0 off SO(d)).
    if (memSaturation > 0) {
        EXPECT_GT(saturatedLanes, lanesChecked / 4);
    }
}

} // namespace

TEST(CellBandTerms, SameBitsAsPerSimplexCode2D)
{
    checkAgainstPerSimplexCode<2>(5);
}

TEST(CellBandTerms, SameBitsAsPerSimplexCode3D)
{
    checkAgainstPerSimplexCode<3>(13);
}

// The membrane saturation psi_s (math/Saturation.h, an addition to the paper) in both codes.
TEST(CellBandTerms, SameBitsAsPerSimplexCodeSaturatedMembrane2D)
{
    checkAgainstPerSimplexCode<2>(7, 0.1);
}

TEST(CellBandTerms, SameBitsAsPerSimplexCodeSaturatedMembrane3D)
{
    checkAgainstPerSimplexCode<3>(17, 0.1);
}
