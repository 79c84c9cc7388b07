/// @file TestEnergy.cc
/// @brief Properties of the assembled energy: zero for identical shapes and phi = Id, +inf for an
///        inverted simplex, independence of the thread count, the structure of the directional
///        energy, the null-Lagrangian property of the volume terms, and value() giving the
///        energy of valueAndGradient() to the last bit.
#include "energy/EnergyFixture.h"

#include <vdbmatch/energy/LandmarkTerm.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

template <int D>
void
checkIdentityIsZero(int level)
{
    auto sdf = D == 3 ? targetSdf<D>(level) : targetSdf<D>(level);
    MatchingProblem<D> P(level, sdf, sdf, EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const NodeVectors<D> u = NodeVectors<D>::Zero(D, P.lattice->nodeCount());
    EnergyTerms t;
    NodeVectors<D> g;
    const Real e = P.energy->valueAndGradient(u, g, &t);
    EXPECT_GT(t.bandSimplices, 100u);
    const Real tol = 1e-12;
    for (int h = 0; h < 2; ++h) {
        EXPECT_NEAR(t.match[h], 0, tol);
        EXPECT_NEAR(t.mem[h], 0, tol);
        EXPECT_NEAR(t.bend[h], 0, tol);
        EXPECT_NEAR(t.vol[h], 0, tol);
    }
    EXPECT_NEAR(e, 0, 8 * tol);
    // phi = Id is a critical point for identical shapes (interior nodes).
    Real gmax = 0;
    for (std::size_t i = 0; i < P.lattice->nodeCount(); ++i)
        if (!P.lattice->isBoundaryNode(i)) gmax = std::max(gmax, g.col(i).norm());
    EXPECT_LT(gmax, 1e-9);
}

} // namespace

TEST(Energy, IdenticalShapesIdentityIsZero3D)
{
    checkIdentityIsZero<3>(4);
}
TEST(Energy, IdenticalShapesIdentityIsZero2D)
{
    checkIdentityIsZero<2>(6);
}

TEST(Energy, InvertedSimplexGivesInfinity)
{
    const int level = 4;
    MatchingProblem<3> P(level, sourceSdf<3>(level), targetSdf<3>(level),
                         EnergyParameters::defaults(3), EnergyKind::Symmetric);
    NodeVectors<3> u = NodeVectors<3>::Zero(3, P.lattice->nodeCount());
    // Push one interior node through its neighbour: several simplices flip.
    const int32_t i = P.lattice->findNode(openvdb::Coord(5, 5, 5));
    ASSERT_GE(i, 0);
    u(0, i) = 1.5 * P.lattice->h();
    EnergyTerms t;
    NodeVectors<3> g;
    const Real e = P.energy->valueAndGradient(u, g, &t);
    EXPECT_EQ(e, INF);
    EXPECT_FALSE(std::isnan(e));
    EXPECT_GT(t.invertedSimplices, 0u);
    EXPECT_LE(P.energy->minJacobianDeterminant(u), 0.0);
    EXPECT_TRUE(g.allFinite());
    // Exactly degenerate (det = 0) also counts as inverted.
    u(0, i) = P.lattice->h();
    EXPECT_EQ(P.energy->value(u), INF);
    // The directional energy too.
    MatchingProblem<3> Q(level, sourceSdf<3>(level), targetSdf<3>(level),
                         EnergyParameters::defaults(3), EnergyKind::Directional);
    EXPECT_EQ(Q.energy->value(u), INF);
}

template <int D>
void
checkThreadIndependence(int level)
{
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level),
                         EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const NodeVectors<D> u = P.randomDisplacement(4, 0.5 * P.lattice->h());
    NodeVectors<D> g1, g2, gs;
    Real e1, e2;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        e1 = P.energy->valueAndGradient(u, g1);
    }
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
        e2 = P.energy->valueAndGradient(u, g2);
    }
    const Real es = P.energy->valueAndGradient(u, gs, nullptr, /*threaded=*/false);
    EXPECT_EQ(e1, e2);
    EXPECT_EQ(e1, es);
    EXPECT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ((g1 - gs).cwiseAbs().maxCoeff(), 0.0);
    EXPECT_EQ(P.energy->value(u), e1);
}

TEST(Energy, ThreadCountIndependent3D)
{
    checkThreadIndependence<3>(4);
}
TEST(Energy, ThreadCountIndependent2D)
{
    checkThreadIndependence<2>(6);
}

TEST(Energy, DirectionalHasOnlyDirectHalves)
{
    const int level = 4;
    MatchingProblem<3> S(level, sourceSdf<3>(level), targetSdf<3>(level),
                         EnergyParameters::defaults(3), EnergyKind::Symmetric);
    MatchingProblem<3> Dir(level, sourceSdf<3>(level), targetSdf<3>(level),
                           EnergyParameters::defaults(3), EnergyKind::Directional);
    const NodeVectors<3> u = S.randomDisplacement(2, 0.4 * S.lattice->h());
    EnergyTerms ts, td;
    S.energy->value(u, &ts);
    Dir.energy->value(u, &td);
    // Direct band halves coincide; inverse halves vanish; volume uses W_vol.
    EXPECT_EQ(ts.match[0], td.match[0]);
    EXPECT_EQ(ts.mem[0], td.mem[0]);
    EXPECT_EQ(ts.bend[0], td.bend[0]);
    EXPECT_EQ(td.match[1] + td.mem[1] + td.bend[1] + td.vol[1], 0.0);
    EXPECT_GT(ts.match[1], 0.0);
    EXPECT_NE(ts.vol[0], td.vol[0]);
    // sigma and coefficients: sigma = 2h by default
    EXPECT_DOUBLE_EQ(S.energy->sigma(), 2.0 / 16);
}

TEST(Energy, VolumeTermsAreStationaryAtIdentity)
{
    // W(1) = 0 is a minimum; for W_vol (3D, not stationary pointwise, see StoredEnergy.h) the
    // Dirichlet condition makes phi = Id stationary: the nodal gradient vanishes in the interior.
    const int level = 3;
    for (EnergyKind kind : {EnergyKind::Symmetric, EnergyKind::Directional}) {
        MatchingProblem<3> P(level, sourceSdf<3>(level), targetSdf<3>(level), singleTerm(3, 3),
                             kind);
        NodeVectors<3> g;
        P.energy->valueAndGradient(NodeVectors<3>::Zero(3, P.lattice->nodeCount()), g);
        for (std::size_t i = 0; i < P.lattice->nodeCount(); ++i)
            if (!P.lattice->isBoundaryNode(i)) {
                EXPECT_LT(g.col(i).norm(), 1e-12) << toString(kind);
            }
    }
}

TEST(Energy, RejectsBadInput)
{
    const int level = 3;
    EnergyParameters bad = EnergyParameters::defaults(3);
    bad.tau = 0;
    EXPECT_THROW(MatchingProblem<3>(level, sourceSdf<3>(level), targetSdf<3>(level), bad,
                                    EnergyKind::Symmetric),
                 openvdb::ValueError);
    MatchingProblem<3> P(level, sourceSdf<3>(level), targetSdf<3>(level),
                         EnergyParameters::defaults(3), EnergyKind::Symmetric);
    EXPECT_THROW(P.energy->value(NodeVectors<3>::Zero(3, 5)), openvdb::ValueError);
}

namespace {

/// The cell culling of the inverse band (Energy::setCellCulling) changes nothing: value,
/// terms, band counts and gradient are bitwise those of the unculled assembly, for
/// displacements from a fraction of a cell to several cells.
template <int D>
void
checkCullingIsExact(int level)
{
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level),
                         EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const Real h = P.lattice->h();
    for (Real amplitude : {0.3 * h, 1.0 * h, 3.0 * h}) {
        // Random up to a cell; beyond, a smooth bump (no noise, which would invert simplices).
        NodeVectors<D> u = P.randomDisplacement(7, std::min(amplitude, h));
        if (amplitude > h) {
            for (std::size_t i = 0; i < P.lattice->nodeCount(); ++i) {
                const Vec<D> x = P.lattice->nodePosition(i);
                Real bump = amplitude;
                for (int a = 0; a < D; ++a)
                    bump *= std::sin(M_PI * x[a]);
                u.col(i) = bump * Vec<D>::Ones();
            }
        }
        EnergyTerms culled, full;
        NodeVectors<D> gCulled, gFull;
        P.energy->setCellCulling(true);
        const Real eCulled = P.energy->valueAndGradient(u, gCulled, &culled);
        P.energy->setCellCulling(false);
        const Real eFull = P.energy->valueAndGradient(u, gFull, &full);
        P.energy->setCellCulling(true);
        ASSERT_TRUE(std::isfinite(eFull)) << "amplitude " << amplitude / h << " h";
        EXPECT_EQ(eCulled, eFull);
        EXPECT_EQ(culled.bandSimplices, full.bandSimplices);
        EXPECT_GT(full.bandSimplices, 0u);
        for (int k = 0; k < 2; ++k) {
            EXPECT_EQ(culled.match[k], full.match[k]);
            EXPECT_EQ(culled.mem[k], full.mem[k]);
            EXPECT_EQ(culled.bend[k], full.bend[k]);
            EXPECT_EQ(culled.vol[k], full.vol[k]);
        }
        EXPECT_EQ((gCulled - gFull).cwiseAbs().maxCoeff(), 0.0);
    }
}

} // namespace

TEST(Energy, CellCullingIsExact3D)
{
    checkCullingIsExact<3>(4);
}
TEST(Energy, CellCullingIsExact2D)
{
    checkCullingIsExact<2>(6);
}

namespace {

/// The inverse-band samples kept between evaluations (Energy::inInverseBand) change nothing:
/// along a path of small steps (a tenth of a cell, as a descent takes them) that carries
/// simplices into and out of the band of M2, every evaluation of the energy that kept its
/// samples is bitwise that of a new energy, which samples every simplex.
template <int D>
void
checkKeptInverseBandIsExact(int level)
{
    const EnergyParameters params = EnergyParameters::defaults(D);
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level), params,
                         EnergyKind::Symmetric);
    const Real h = P.lattice->h();
    // A smooth bump of 2.5 cells, reached in 25 steps.
    NodeVectors<D> bump(D, P.lattice->nodeCount());
    for (std::size_t i = 0; i < P.lattice->nodeCount(); ++i) {
        const Vec<D> x = P.lattice->nodePosition(i);
        Real b = 2.5 * h;
        for (int a = 0; a < D; ++a)
            b *= std::sin(M_PI * x[a]);
        bump.col(i) = b * Vec<D>::Ones();
    }
    constexpr int STEPS = 25;
    std::size_t fewest = std::numeric_limits<std::size_t>::max(), most = 0;
    for (int k = 0; k <= STEPS; ++k) {
        const NodeVectors<D> u = (Real(k) / STEPS) * bump;
        EnergyTerms kept, fresh;
        NodeVectors<D> gKept, gFresh;
        // Value-only evaluations keep samples too: one between the gradients.
        if (k % 2) P.energy->value(u, nullptr);
        const Real eKept = P.energy->valueAndGradient(u, gKept, &kept);
        const Energy<D> newEnergy(*P.lattice, *P.shape1, *P.shape2, params, EnergyKind::Symmetric);
        const Real eFresh = newEnergy.valueAndGradient(u, gFresh, &fresh);
        ASSERT_TRUE(std::isfinite(eFresh)) << "step " << k;
        EXPECT_EQ(eKept, eFresh) << "step " << k;
        EXPECT_EQ(kept.bandSimplices, fresh.bandSimplices) << "step " << k;
        for (int t = 0; t < 2; ++t) {
            EXPECT_EQ(kept.match[t], fresh.match[t]) << "step " << k;
            EXPECT_EQ(kept.mem[t], fresh.mem[t]) << "step " << k;
        }
        EXPECT_EQ((gKept - gFresh).cwiseAbs().maxCoeff(), 0.0) << "step " << k;
        fewest = std::min(fewest, fresh.bandSimplices);
        most = std::max(most, fresh.bandSimplices);
    }
    // The path moves simplices across the band's edge (else the test would test nothing).
    EXPECT_LT(fewest, most);
}

} // namespace

TEST(Energy, KeptInverseBandSamplesAreExact3D)
{
    checkKeptInverseBandIsExact<3>(4);
}
TEST(Energy, KeptInverseBandSamplesAreExact2D)
{
    checkKeptInverseBandIsExact<2>(6);
}

TEST(Energy, ConstantOffsetIsTheEnergyOfTheIdentityForIdenticalShapes)
{
    // Energy::constantOffset: c_vol sigma^theta W_vol(1)|Omega| for the directional energy (the
    // value of every phi = Id between identical shapes), 0 for the symmetric one.
    for (int level : {3, 4}) {
        const auto sdf = targetSdf<3>(level);
        MatchingProblem<3> dir(level, sdf, sdf, EnergyParameters::defaults(3),
                               EnergyKind::Directional);
        MatchingProblem<3> sym(level, sdf, sdf, EnergyParameters::defaults(3),
                               EnergyKind::Symmetric);
        const NodeVectors<3> u = NodeVectors<3>::Zero(3, dir.lattice->nodeCount());
        const Real e = dir.energy->value(u);
        EXPECT_GT(e, 0.0);
        EXPECT_NEAR(dir.energy->constantOffset(), e, 1e-12 * e);
        EXPECT_EQ(sym.energy->constantOffset(), 0.0);
    }
}

namespace {

/// value() and valueAndGradient() give the same energy and terms, bit for bit: the descent's
/// line search evaluates its trials with either (DescentOptions::gradientAtTrials), and the
/// iterates must not depend on which.
template <int D>
void
checkValueIsTheValueOfValueAndGradient(int level, EnergyKind kind)
{
    MatchingProblem<D> P(level, sourceSdf<D>(level), targetSdf<D>(level),
                         EnergyParameters::defaults(D), kind);
    LandmarkPairs<D> pairs;
    pairs.weight = 30;
    for (int k = 0; k < 4; ++k) {
        Vec<D> a = Vec<D>::Constant(0.5);
        a[0] += 0.05 * k;
        pairs.source.push_back(a);
        pairs.target.push_back(a + Vec<D>::Constant(0.01 * (k + 1)));
    }
    const energy::LandmarkTerm<D> landmarks(*P.lattice, pairs);
    std::size_t compared = 0;
    for (const energy::LandmarkTerm<D>* lm :
         {static_cast<const energy::LandmarkTerm<D>*>(nullptr), &landmarks}) {
        P.energy->setLandmarks(lm);
        for (unsigned seed = 1; seed <= 6; ++seed) {
            const NodeVectors<D> u = P.randomDisplacement(seed, 0.15 * seed * P.lattice->h());
            EnergyTerms tv, tg;
            NodeVectors<D> g;
            const Real ev = P.energy->value(u, &tv);
            const Real eg = P.energy->valueAndGradient(u, g, &tg);
            ASSERT_TRUE(std::isfinite(eg)) << "seed " << seed;
            EXPECT_EQ(ev, eg) << "seed " << seed << ", relative difference " << (ev - eg) / eg;
            for (int h = 0; h < 2; ++h) {
                EXPECT_EQ(tv.match[h], tg.match[h]);
                EXPECT_EQ(tv.mem[h], tg.mem[h]);
                EXPECT_EQ(tv.bend[h], tg.bend[h]);
                EXPECT_EQ(tv.vol[h], tg.vol[h]);
            }
            EXPECT_EQ(tv.landmark, tg.landmark);
            EXPECT_EQ(tv.bandSimplices, tg.bandSimplices);
            if (lm) {
                EXPECT_GT(tg.landmark, 0);
            }
            ++compared;
        }
    }
    P.energy->setLandmarks(nullptr);
    EXPECT_EQ(compared, 12u);
}

} // namespace

TEST(Energy, ValueIsTheValueOfValueAndGradientSymmetric3D)
{
    checkValueIsTheValueOfValueAndGradient<3>(4, EnergyKind::Symmetric);
}
TEST(Energy, ValueIsTheValueOfValueAndGradientDirectional3D)
{
    checkValueIsTheValueOfValueAndGradient<3>(4, EnergyKind::Directional);
}
TEST(Energy, ValueIsTheValueOfValueAndGradientSymmetric2D)
{
    checkValueIsTheValueOfValueAndGradient<2>(6, EnergyKind::Symmetric);
}
TEST(Energy, ValueIsTheValueOfValueAndGradientDirectional2D)
{
    checkValueIsTheValueOfValueAndGradient<2>(6, EnergyKind::Directional);
}
