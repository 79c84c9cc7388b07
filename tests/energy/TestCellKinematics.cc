/// @file TestCellKinematics.cc
/// @brief CellKinematics (the kinematics and the volume term of eq:EsymVol for the simplices of
///        a cell, lane by lane) computes the same bits as the per-simplex code it replaces in the
///        energy loop: SimplexKinematics, volumeDirect, volumeInverse and DensityGradient::finish.
///        The energy's results are bitwise independent of this choice only if every lane
///        repeats Eigen's evaluation order; a reordered sum fails here on most inputs.
#include "support/RandomMatrices.h"
#include "support/SameBits.h"

#include <vdbmatch/energy/CellKinematics.h>
#include <vdbmatch/energy/VolumeTerm.h>

#include <gtest/gtest.h>

#include <array>

using namespace vdbmatch;
using namespace vdbmatch::energy;
using vdbmatch::test::sameBits;

namespace {

template <int D>
void
checkAgainstPerSimplexCode(unsigned seed)
{
    constexpr int N = CellKinematics<D>::N;
    test::RandomSource random(seed);
    const Real c = 0.37; // c_vol sigma^theta
    int lanesChecked = 0, negative = 0;
    for (int trial = 0; trial < 4000; ++trial) {
        CellKinematics<D> ck;
        std::array<Mat<D>, N> A;
        for (int p = 0; p < N; ++p) {
            // Near the identity (the common case), far from it, and some with det A <= 0.
            const int kind = (trial + p) % 3;
            A[p] = kind == 0   ? random.positiveMatrix<D>(0.3)
                   : kind == 1 ? random.matrix<D>(2.0)
                               : Mat<D>(Mat<D>::Identity() + random.matrix<D>(0.05));
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    ck.A[i][j][p] = A[p](i, j);
        }
        ck.kinematics();
        CellKinematics<D> values = ck;
        values.template symmetricVolume<false>(c);
        ck.template symmetricVolume<true>(c);
        // A band term's share of dB, added between the volume term and finish(), as in the loop.
        std::array<Mat<D>, N> band;
        for (int p = 0; p < N; ++p) {
            band[p] = random.matrix<D>(0.5);
            DensityGradient<D> g;
            ck.loadGradient(p, g);
            g.dB += band[p];
            ck.storeGradient(p, g);
        }
        ck.finish();
        for (int p = 0; p < N; ++p) {
            const SimplexKinematics<D> k(A[p]);
            ASSERT_TRUE(sameBits(k.J, ck.J[p])) << "det, trial " << trial << " lane " << p;
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    ASSERT_TRUE(sameBits(k.C(i, j), ck.C[i][j][p])) << "cof " << i << j;
            if (!(k.J > 0)) {
                ++negative;
                continue; // the energy loop skips the lane (+inf energy)
            }
            const SimplexKinematics<D> copy = ck.simplex(p);
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    ASSERT_TRUE(sameBits(k.B(i, j), copy.B(i, j))) << "inverse " << i << j;
            DensityGradient<D> g;
            const Real direct = volumeDirect<D, true>(k, c, &g);
            const Real inverse = volumeInverse<D, true>(k, c, &g);
            g.dB += band[p];
            g.finish(k);
            ASSERT_TRUE(sameBits(direct, ck.volumeDirect[p])) << "trial " << trial << " lane " << p;
            ASSERT_TRUE(sameBits(inverse, ck.volumeInverse[p]));
            ASSERT_TRUE(sameBits(volumeDirect<D, false>(k, c, nullptr), values.volumeDirect[p]));
            ASSERT_TRUE(sameBits(volumeInverse<D, false>(k, c, nullptr), values.volumeInverse[p]));
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    ASSERT_TRUE(sameBits(g.dA(i, j), ck.dA[i][j][p]))
                        << "dE/dA(" << i << "," << j << "), trial " << trial << " lane " << p;
            ++lanesChecked;
        }
    }
    EXPECT_GT(lanesChecked, 1000);
    EXPECT_GT(negative, 10); // the det <= 0 lanes were exercised too
}

} // namespace

TEST(CellKinematics, SameBitsAsPerSimplexCode2D)
{
    checkAgainstPerSimplexCode<2>(7);
}

TEST(CellKinematics, SameBitsAsPerSimplexCode3D)
{
    checkAgainstPerSimplexCode<3>(11);
}
