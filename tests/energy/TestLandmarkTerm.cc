/// @file TestLandmarkTerm.cc
/// @brief The landmark term (an addition to the paper's energy): its value is
///        c_lm/K sum |phi(a_k) - b_k|^2 with phi the P1 interpolant, its gradient is exact
///        (finite differences of the whole energy with landmarks), it is zero when phi maps each
///        a_k to b_k, and bad input is refused.
#include "energy/EnergyFixture.h"

#include <vdbmatch/energy/LandmarkTerm.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <random>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

/// Landmarks near the sphere of the fixture, with targets a small shift away.
template <int D>
LandmarkPairs<D>
somePairs(unsigned seed, std::size_t count, Real weight)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> U(-1, 1);
    LandmarkPairs<D> pairs;
    pairs.weight = weight;
    for (std::size_t k = 0; k < count; ++k) {
        Vec<D> a, shift;
        for (int i = 0; i < D; ++i) {
            a[i] = 0.5 + 0.3 * U(rng);
            shift[i] = 0.02 * U(rng);
        }
        pairs.source.push_back(a);
        pairs.target.push_back(a + shift);
    }
    return pairs;
}

template <int D>
void
checkGradientWithLandmarks(int level)
{
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level),
                         EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const LandmarkPairs<D> pairs = somePairs<D>(7, 5, 50.0);
    const energy::LandmarkTerm<D> term(*P.lattice, pairs);
    for (unsigned seed = 1; seed <= 2; ++seed) {
        const NodeVectors<D> u = P.randomDisplacement(seed, 0.3 * P.lattice->h());
        NodeVectors<D> g0, g;
        EnergyTerms t0, t;
        P.energy->setLandmarks(nullptr);
        const Real e0 = P.energy->valueAndGradient(u, g0, &t0);
        P.energy->setLandmarks(&term);
        const Real e = P.energy->valueAndGradient(u, g, &t);
        EXPECT_EQ(t0.landmark, 0);
        EXPECT_GT(t.landmark, 0);
        EXPECT_NEAR(e - e0, t.landmark, 1e-12 * std::abs(e));
        EXPECT_DOUBLE_EQ(t.landmark, term.value(u));
        // E_lm by its definition, with phi(a_k) from the interpolator.
        const multiscale::PiecewiseLinearInterpolator<D> phi(*P.lattice);
        Real expected = 0;
        for (std::size_t k = 0; k < pairs.source.size(); ++k) {
            Vec<D> du;
            ASSERT_TRUE(phi.evaluate(u, pairs.source[k], du));
            expected += (pairs.source[k] + du - pairs.target[k]).squaredNorm();
        }
        expected *= pairs.weight / Real(pairs.source.size());
        EXPECT_NEAR(t.landmark, expected, 1e-14);

        // The gradient of the whole energy with landmarks, by central differences (the term is
        // quadratic, so the landmark part is exact up to rounding).
        const NodeVectors<D> v = P.randomDirection(100 + seed);
        const Real slope = g.cwiseProduct(v).sum();
        const Real eps = 1e-4;
        auto E = [&](Real s) { return P.energy->value(u + s * v); };
        const Real fd = (8 * (E(eps) - E(-eps)) - (E(2 * eps) - E(-2 * eps))) / (12 * eps);
        EXPECT_LE(std::abs(fd - slope), 1e-6 * std::abs(slope)) << "seed " << seed;
        // ... and the landmark part alone.
        const NodeVectors<D> dg = g - g0;
        const Real lmSlope = dg.cwiseProduct(v).sum();
        auto L = [&](Real s) { return term.value(u + s * v); };
        EXPECT_NEAR((L(eps) - L(-eps)) / (2 * eps), lmSlope, 1e-7 * std::abs(lmSlope) + 1e-12);
        P.energy->setLandmarks(nullptr);
    }
}

} // namespace

TEST(LandmarkTerm, GradientIsExact3D)
{
    checkGradientWithLandmarks<3>(4);
}

TEST(LandmarkTerm, GradientIsExact2D)
{
    checkGradientWithLandmarks<2>(6);
}

TEST(LandmarkTerm, ZeroWhenPhiMapsEachLandmarkOntoItsTarget)
{
    // phi = Id + t: an affine map is exact in P1, so phi(a_k) = a_k + t = b_k.
    const SimplexLattice<2> lattice = SimplexLattice<2>::dense(5);
    LandmarkPairs<2> pairs = somePairs<2>(3, 4, 10.0);
    const Vec<2> shift(0.013, -0.007);
    for (std::size_t k = 0; k < pairs.source.size(); ++k)
        pairs.target[k] = pairs.source[k] + shift;
    NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        u.col(i) = shift;
    const energy::LandmarkTerm<2> term(lattice, pairs);
    EXPECT_NEAR(term.value(u), 0, 1e-28);
    Real mean = 1, max = 1;
    term.residual(u, mean, max);
    EXPECT_NEAR(max, 0, 1e-15);
    NodeVectors<2> g = NodeVectors<2>::Zero(2, lattice.nodeCount());
    term.addGradient(u, g);
    EXPECT_LT(g.cwiseAbs().maxCoeff(), 1e-13);
    // At phi = Id the residual is the shift.
    term.residual(NodeVectors<2>::Zero(2, lattice.nodeCount()), mean, max);
    EXPECT_NEAR(mean, shift.norm(), 1e-15);
}

TEST(LandmarkTerm, RefusesBadInput)
{
    const SimplexLattice<2> lattice = SimplexLattice<2>::dense(4);
    LandmarkPairs<2> pairs = somePairs<2>(5, 3, 1.0);
    LandmarkPairs<2> uneven = pairs;
    uneven.target.pop_back();
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, uneven), openvdb::ValueError);
    LandmarkPairs<2> negative = pairs;
    negative.weight = -1;
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, negative), openvdb::ValueError);
    LandmarkPairs<2> outside = pairs;
    outside.source[1] = Vec<2>(1.5, 0.5);
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, outside), openvdb::ValueError);
    LandmarkPairs<2> notFinite = pairs;
    notFinite.target[2][0] = std::nan("");
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, notFinite), openvdb::ValueError);
}

TEST(LandmarkTerm, PairWeightsWeighEachPair)
{
    // w_k = c_lm / K for every pair is the plain term; unequal weights give
    // sum_k w_k |phi(a_k) - b_k|^2 and its exact gradient (central differences of a quadratic).
    const SimplexLattice<2> lattice = SimplexLattice<2>::dense(5);
    const LandmarkPairs<2> plain = somePairs<2>(11, 6, 30.0);
    LandmarkPairs<2> even = plain;
    even.weight = 0; // unused with pair weights
    even.pairWeights.assign(6, 30.0 / 6);
    LandmarkPairs<2> uneven = plain;
    uneven.pairWeights = {1.0, 0.0, 7.0, 0.5, 3.0, 20.0};
    const energy::LandmarkTerm<2> a(lattice, plain), b(lattice, even), c(lattice, uneven);
    std::mt19937 rng(4);
    std::uniform_real_distribution<Real> U(-0.01, 0.01);
    NodeVectors<2> u(2, lattice.nodeCount());
    for (Eigen::Index i = 0; i < u.size(); ++i)
        u.data()[i] = U(rng);
    EXPECT_NEAR(b.value(u), a.value(u), 1e-14 * a.value(u));
    Real expected = 0;
    for (std::size_t k = 0; k < 6; ++k)
        expected += uneven.pairWeights[k] * (c.mapped(u, k) - uneven.target[k]).squaredNorm();
    EXPECT_NEAR(c.value(u), expected, 1e-15);
    NodeVectors<2> g = NodeVectors<2>::Zero(2, lattice.nodeCount());
    EXPECT_DOUBLE_EQ(c.addGradient(u, g), c.value(u));
    NodeVectors<2> v(2, lattice.nodeCount());
    for (Eigen::Index i = 0; i < v.size(); ++i)
        v.data()[i] = U(rng);
    const Real eps = 1e-3, slope = g.cwiseProduct(v).sum();
    const Real fd = (c.value(u + eps * v) - c.value(u - eps * v)) / (2 * eps);
    EXPECT_NEAR(fd, slope, 1e-9 * std::abs(slope) + 1e-15);
    // With every weight 0 the term vanishes, whatever c_lm.
    LandmarkPairs<2> only = uneven;
    only.pairWeights = {0, 0, 0, 0, 0, 0};
    EXPECT_EQ(energy::LandmarkTerm<2>(lattice, only).value(u), 0);
    // Bad weights are refused.
    LandmarkPairs<2> shortList = uneven;
    shortList.pairWeights.pop_back();
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, shortList), openvdb::ValueError);
    LandmarkPairs<2> negative = uneven;
    negative.pairWeights[2] = -1;
    EXPECT_THROW(energy::LandmarkTerm<2>(lattice, negative), openvdb::ValueError);
}
