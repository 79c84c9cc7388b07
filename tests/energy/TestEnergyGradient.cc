/// @file TestEnergyGradient.cc
/// @brief The gradient is the derivative of the discrete energy: central differences along random
///        directions from random states with det D phi > 0, every term, both energies, 2D and 3D,
///        and the Taylor remainder of second order.
#include "energy/EnergyFixture.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

constexpr Real GRADIENT_TOLERANCE = 1e-6; ///< relative error of the directional derivative

Real
dot(const NodeVectors<2>& a, const NodeVectors<2>& b)
{
    return a.cwiseProduct(b).sum();
}
Real
dot(const NodeVectors<3>& a, const NodeVectors<3>& b)
{
    return a.cwiseProduct(b).sum();
}

template <int D>
void
checkGradient(EnergyKind kind, int term, int level, Real membraneSaturation = 0)
{
    EnergyParameters params = term < 0 ? EnergyParameters::defaults(D) : singleTerm(D, term);
    params.membraneSaturation = membraneSaturation;
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level), params, kind);
    const std::string what = std::string(toString(kind)) + " " +
                             (term < 0 ? "total" : termName(term)) + " " + std::to_string(D) + "D" +
                             (membraneSaturation > 0 ? " saturated membrane" : "");
    for (unsigned seed = 1; seed <= 3; ++seed) {
        const NodeVectors<D> u = P.randomDisplacement(seed, 0.3 * P.lattice->h() * seed);
        ASSERT_GT(P.energy->minJacobianDeterminant(u), 0.2) << what;
        NodeVectors<D> g;
        EnergyTerms terms;
        const Real e = P.energy->valueAndGradient(u, g, &terms);
        ASSERT_TRUE(std::isfinite(e)) << what;
        ASSERT_GT(terms.bandSimplices, 0u);
        if (term >= 0 && term < 3) {
            // the band term is active in both halves (symmetric) so both are checked
            const Real* halves[3] = {terms.match, terms.mem, terms.bend};
            EXPECT_GT(halves[term][0], 0) << what;
            if (kind == EnergyKind::Symmetric) {
                EXPECT_GT(halves[term][1], 0) << what;
            }
        }
        const NodeVectors<D> v = P.randomDirection(100 + seed);
        const Real slope = dot(g, v);
        // Fourth-order central difference (truncation O(eps^4)), so that directions where the
        // slope is small compared with the curvature of E (e.g. the null-Lagrangian volume
        // terms near phi = Id) are still checked to 1e-6.
        const Real eps = 1e-4;
        auto E = [&](Real t) { return P.energy->value(u + t * v); };
        const Real fd = (8 * (E(eps) - E(-eps)) - (E(2 * eps) - E(-2 * eps))) / (12 * eps);
        EXPECT_LE(std::abs(fd - slope), GRADIENT_TOLERANCE * std::abs(slope))
            << what << " seed " << seed << ": finite difference " << fd << " gradient " << slope;

        // Taylor remainder |E(u + t v) - E(u) - t g.v| = O(t^2).
        if (seed == 1) {
            Real prev = 0;
            std::vector<Real> orders;
            for (Real t : {0.04, 0.02, 0.01, 0.005}) {
                const Real r = std::abs(P.energy->value(u + t * v) - e - t * slope);
                if (prev > 0) orders.push_back(std::log2(prev / r));
                prev = r;
            }
            for (Real o : orders) {
                EXPECT_GT(o, 1.7) << what << ": Taylor remainder order " << o;
                EXPECT_LT(o, 2.3) << what << ": Taylor remainder order " << o;
            }
        }
    }
}

} // namespace

TEST(EnergyGradient, Symmetric3DPerTerm)
{
    for (int term = -1; term < 4; ++term)
        checkGradient<3>(EnergyKind::Symmetric, term, 4);
}
TEST(EnergyGradient, Directional3DPerTerm)
{
    for (int term = -1; term < 4; ++term)
        checkGradient<3>(EnergyKind::Directional, term, 4);
}
TEST(EnergyGradient, Symmetric2DPerTerm)
{
    for (int term = -1; term < 4; ++term)
        checkGradient<2>(EnergyKind::Symmetric, term, 6);
}
TEST(EnergyGradient, Directional2DPerTerm)
{
    for (int term = -1; term < 4; ++term)
        checkGradient<2>(EnergyKind::Directional, term, 6);
}
// The membrane saturation (math/Saturation.h, an addition to the paper): s = 0.02 lies within
// the membrane densities of these states, so psi_s bends them (SaturationLowersOnlyTheMembrane).
TEST(EnergyGradient, SaturatedMembrane3D)
{
    checkGradient<3>(EnergyKind::Symmetric, 1, 4, 0.02);
    checkGradient<3>(EnergyKind::Directional, 1, 4, 0.02);
    checkGradient<3>(EnergyKind::Symmetric, -1, 4, 0.02);
}
TEST(EnergyGradient, SaturatedMembrane2D)
{
    checkGradient<2>(EnergyKind::Symmetric, 1, 6, 0.02);
    checkGradient<2>(EnergyKind::Directional, 1, 6, 0.02);
    checkGradient<2>(EnergyKind::Symmetric, -1, 6, 0.02);
}

/// On the states of the gradient checks, s = 0.02 lowers both membrane halves by a sizeable
/// fraction and leaves the other terms bit for bit.
template <int D>
void
checkSaturationLowersOnlyTheMembrane(int level)
{
    EnergyParameters paper = EnergyParameters::defaults(D), saturated = paper;
    saturated.membraneSaturation = 0.02;
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level), paper,
                         EnergyKind::Symmetric);
    MatchingProblem<D> S(level, sourceSdf<D>(level), targetSdf<D>(level), saturated,
                         EnergyKind::Symmetric);
    for (unsigned seed = 1; seed <= 3; ++seed) {
        const NodeVectors<D> u = P.randomDisplacement(seed, 0.3 * P.lattice->h() * seed);
        EnergyTerms a, b;
        P.energy->value(u, &a);
        S.energy->value(u, &b);
        for (int k = 0; k < 2; ++k) {
            EXPECT_LT(b.mem[k], 0.97 * a.mem[k]) << D << "D seed " << seed << " half " << k;
            EXPECT_GT(b.mem[k], 0.0);
            EXPECT_EQ(b.match[k], a.match[k]);
            EXPECT_EQ(b.bend[k], a.bend[k]);
            EXPECT_EQ(b.vol[k], a.vol[k]);
        }
    }
}
TEST(EnergyGradient, SaturationLowersOnlyTheMembrane)
{
    checkSaturationLowersOnlyTheMembrane<3>(4);
    checkSaturationLowersOnlyTheMembrane<2>(6);
}
