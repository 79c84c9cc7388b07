/// @file TestInnerDistanceTerm.cc
/// @brief The inner-distance term (an addition to the paper's energy): its value is
///        sum_i w_i max(|F2(phi(p_i)) - F1_i| - tau, 0)^2 with phi the P1 interpolant, its
///        gradient is exact (finite differences of the whole energy with the term), it vanishes
///        when phi keeps F within the tolerance (a turn of a shape and its field), and bad input
///        is refused.
#include "energy/EnergyFixture.h"
#include "support/TestSurfaces.h"

#include <vdbmatch/energy/InnerDistanceTerm.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <random>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

template <int D>
Surface<D>
roundShape(const Vec<D>& centre, double radius)
{
    if constexpr (D == 2)
        return circle(centre, radius, 300);
    else
        return uvSphere(centre, radius, 24, 48);
}

/// Points near the sphere of the fixture with values off F2 there by up to 0.05, so that some
/// lie within the tolerance and some beyond.
template <int D>
InnerDistanceSamples<D>
someSamples(unsigned seed, std::size_t count, Real tolerance)
{
    Vec<D> c = Vec<D>::Constant(0.5), source = c;
    source[0] = 0.35;
    auto field = std::make_shared<InnerDistanceField<D>>(
        innerDistanceFields<D>(roundShape<D>(c, 0.3), {source}, D == 2 ? 7 : 5)[0]);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> U(-1, 1);
    InnerDistanceSamples<D> s;
    s.targets = {field};
    s.tolerance = tolerance;
    for (std::size_t k = 0; k < count; ++k) {
        Vec<D> p;
        for (int i = 0; i < D; ++i)
            p[i] = 0.5 + 0.3 * U(rng);
        Real f;
        field->sample(p, f);
        s.points.push_back(p);
        s.values.push_back(f + 0.05 * U(rng));
        s.weights.push_back(10 + 5 * U(rng));
        s.fields.push_back(0);
    }
    return s;
}

template <int D>
void
checkGradientWithInnerDistance(int level)
{
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level),
                         EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const InnerDistanceSamples<D> samples = someSamples<D>(7, 40, 0.01);
    const energy::InnerDistanceTerm<D> term(*P.lattice, samples);
    for (unsigned seed = 1; seed <= 2; ++seed) {
        const NodeVectors<D> u = P.randomDisplacement(seed, 0.3 * P.lattice->h());
        NodeVectors<D> g0, g;
        EnergyTerms t0, t;
        P.energy->setInnerDistance(nullptr);
        const Real e0 = P.energy->valueAndGradient(u, g0, &t0);
        P.energy->setInnerDistance(&term);
        const Real e = P.energy->valueAndGradient(u, g, &t);
        EXPECT_EQ(t0.innerDistance, 0);
        EXPECT_GT(t.innerDistance, 0);
        EXPECT_NEAR(e - e0, t.innerDistance, 1e-12 * std::abs(e));
        EXPECT_EQ(t.innerDistance, term.value(u));
        // E_F by its definition, with phi(p_i) from the interpolator; some points within the
        // tolerance, some beyond.
        const multiscale::PiecewiseLinearInterpolator<D> phi(*P.lattice);
        Real expected = 0;
        int within = 0;
        for (std::size_t i = 0; i < samples.points.size(); ++i) {
            Vec<D> du;
            ASSERT_TRUE(phi.evaluate(u, samples.points[i], du));
            Real f;
            samples.targets[0]->sample(samples.points[i] + du, f);
            const Real excess = std::max(std::abs(f - samples.values[i]) - samples.tolerance, 0.0);
            within += excess == 0;
            expected += samples.weights[i] * excess * excess;
        }
        EXPECT_GT(within, 0);
        EXPECT_LT(within, int(samples.points.size()));
        EXPECT_NEAR(t.innerDistance, expected, 1e-12 * expected);

        // The gradient of the term by central differences: exact where F2's interpolant is
        // smooth, so a step small against the cells.
        const NodeVectors<D> dg = g - g0;
        const NodeVectors<D> v = P.randomDirection(100 + seed);
        const Real slope = dg.cwiseProduct(v).sum();
        const Real eps = 1e-8;
        auto F = [&](Real s) { return term.value(u + s * v); };
        EXPECT_NEAR((F(eps) - F(-eps)) / (2 * eps), slope, 1e-5 * std::abs(slope) + 1e-9)
            << "seed " << seed;
        NodeVectors<D> alone = NodeVectors<D>::Zero(D, P.lattice->nodeCount());
        EXPECT_EQ(term.addGradient(u, alone), term.value(u));
        EXPECT_LT((alone - dg).cwiseAbs().maxCoeff(), 1e-9 * (1 + alone.cwiseAbs().maxCoeff()));
        P.energy->setInnerDistance(nullptr);
    }
}

} // namespace

TEST(InnerDistanceTerm, GradientIsExact3D)
{
    checkGradientWithInnerDistance<3>(4);
}

TEST(InnerDistanceTerm, GradientIsExact2D)
{
    checkGradientWithInnerDistance<2>(6);
}

TEST(InnerDistanceTerm, ZeroWhenPhiKeepsTheInnerDistance)
{
    // phi = Id + t maps a disc and its source onto the disc shifted by t: F2(p + t) = F1(p) up
    // to the solver's error, which the tolerance covers.
    const SimplexLattice<2> lattice = SimplexLattice<2>::dense(5);
    const Vec<2> c(0.45, 0.5), t(0.04, -0.03);
    const InnerDistanceField<2> f1 =
        innerDistanceFields<2>(circle(c, 0.25, 300), {c + Vec<2>(-0.15, 0)}, 8)[0];
    auto f2 = std::make_shared<InnerDistanceField<2>>(
        innerDistanceFields<2>(circle(c + t, 0.25, 300), {c + t + Vec<2>(-0.15, 0)}, 8)[0]);
    InnerDistanceSamples<2> s;
    s.targets = {f2};
    s.tolerance = 2 * f2->h;
    for (int k = 0; k < 60; ++k) {
        const double a = 2 * M_PI * k / 60;
        const Vec<2> p = c + 0.25 * Vec<2>(std::cos(a), std::sin(a));
        Real f;
        f1.sample(p, f);
        s.points.push_back(p);
        s.values.push_back(f);
        s.weights.push_back(1.0 / 60);
        s.fields.push_back(0);
    }
    const energy::InnerDistanceTerm<2> term(lattice, s);
    NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        u.col(i) = t;
    EXPECT_EQ(term.value(u), 0);
    Real mean = 1, beyond = 1;
    term.residual(u, mean, beyond);
    EXPECT_LT(mean, f2->h);
    EXPECT_EQ(beyond, 0);
    // At phi = Id the points sit where F2 differs by up to |t| = 0.05: the term is positive.
    const NodeVectors<2> zero = NodeVectors<2>::Zero(2, lattice.nodeCount());
    EXPECT_GT(term.value(zero), 0);
    term.residual(zero, mean, beyond);
    EXPECT_GT(beyond, 0.3);
}

TEST(InnerDistanceTerm, RefusesBadInput)
{
    const SimplexLattice<2> lattice = SimplexLattice<2>::dense(4);
    const InnerDistanceSamples<2> s = someSamples<2>(5, 3, 0.01);
    EXPECT_NO_THROW(energy::InnerDistanceTerm<2>(lattice, s));
    InnerDistanceSamples<2> uneven = s;
    uneven.values.pop_back();
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, uneven), openvdb::ValueError);
    InnerDistanceSamples<2> negative = s;
    negative.weights[1] = -1;
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, negative), openvdb::ValueError);
    InnerDistanceSamples<2> tolerance = s;
    tolerance.tolerance = -0.1;
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, tolerance), openvdb::ValueError);
    InnerDistanceSamples<2> outside = s;
    outside.points[1] = Vec<2>(1.5, 0.5);
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, outside), openvdb::ValueError);
    InnerDistanceSamples<2> notFinite = s;
    notFinite.values[2] = std::nan("");
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, notFinite), openvdb::ValueError);
    InnerDistanceSamples<2> noField = s;
    noField.targets[0].reset();
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, noField), openvdb::ValueError);
    InnerDistanceSamples<2> badIndex = s;
    badIndex.fields[1] = 1;
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, badIndex), openvdb::ValueError);
    InnerDistanceSamples<2> fewIndices = s;
    fewIndices.fields.pop_back();
    EXPECT_THROW(energy::InnerDistanceTerm<2>(lattice, fewIndices), openvdb::ValueError);
}
