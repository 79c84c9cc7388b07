/// @file TestDescent.cc
/// @brief The multiscale H^1 conjugate-gradient descent on whole problems: circle -> ellipse
///        (2D, levels 4..6, paper's 2D parameters) and sphere -> ellipsoid (3D, levels 3..5):
///        monotone energy, det D phi > 0 throughout, matching residual below h/2, energy below
///        the identity's; cancellation through the interrupter; serial = threaded; identical
///        shapes stay at the identity. Also the Armijo backtracking on scalar functions.
#include "support/AnalyticShapes.h"

#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/MultiscaleDriver.h>
#include <vdbmatch/multiscale/Prolongation.h>
#include <vdbmatch/solver/ArmijoLineSearch.h>
#include <vdbmatch/solver/Descent.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

using namespace vdbmatch;
using namespace vdbmatch::solver;
using namespace vdbmatch::multiscale;

namespace {

/// M1 = circle (sphere) of radius 0.22 at the centre; M2 = a translated, anisotropically scaled
/// ellipse (ellipsoid).
template <int D> struct Shapes;

template <> struct Shapes<2>
{
    static constexpr int FIELD_LEVEL = 7;
    Vec<2> center1{0.5, 0.5};
    Real radius1 = 0.22;
    test::AnalyticEllipse ellipse{Vec<2>(0.52, 0.49), Vec<2>(0.27, 0.19)};
    openvdb::FloatGrid::Ptr sdf1() const
    {
        return test::createCircleSdf(FIELD_LEVEL, center1, radius1);
    }
    openvdb::FloatGrid::Ptr sdf2() const
    {
        return test::createEllipseSdf(FIELD_LEVEL, ellipse.center(), ellipse.semiAxes());
    }
    /// Points on M1, equally spaced in angle.
    std::vector<Vec<2>> pointsOnM1() const
    {
        std::vector<Vec<2>> pts;
        for (int k = 0; k < 720; ++k) {
            const Real a = 2 * M_PI * k / 720;
            pts.push_back(center1 + radius1 * Vec<2>(std::cos(a), std::sin(a)));
        }
        return pts;
    }
};

template <> struct Shapes<3>
{
    static constexpr int FIELD_LEVEL = 6;
    Vec<3> center1{0.5, 0.5, 0.5};
    Real radius1 = 0.22;
    test::AnalyticEllipsoid<3> ellipse{Vec<3>(0.53, 0.48, 0.5), Vec<3>(0.26, 0.2, 0.23)};
    openvdb::FloatGrid::Ptr sdf1() const
    {
        return test::createSphereSdf(FIELD_LEVEL, center1, radius1);
    }
    openvdb::FloatGrid::Ptr sdf2() const
    {
        return test::createEllipsoidSdf(FIELD_LEVEL, ellipse.center(), ellipse.semiAxes());
    }
    /// Points on M1 from a Fibonacci lattice (about uniform in area).
    std::vector<Vec<3>> pointsOnM1() const
    {
        std::vector<Vec<3>> pts;
        const int n = 2000;
        const Real golden = M_PI * (3 - std::sqrt(5.0));
        for (int k = 0; k < n; ++k) {
            const Real z = 1 - 2 * (k + 0.5) / n, rho = std::sqrt(1 - z * z);
            const Real phi = golden * k;
            pts.push_back(center1 + radius1 * Vec<3>(rho * std::cos(phi), rho * std::sin(phi), z));
        }
        return pts;
    }
};

template <int D> struct Problem
{
    Shapes<D> shapes;
    std::shared_ptr<const FieldSampler<D>> shape1, shape2;

    explicit Problem(const EnergyParameters& params)
    {
        ShapeFieldOptions opts;
        opts.tau = params.tau;
        shape1 = FieldSampler<D>::build({shapes.sdf1()}, opts);
        shape2 = FieldSampler<D>::build({shapes.sdf2()}, opts);
    }

    LevelBuilder<D> denseLevels() const
    {
        return [this](int l) {
            Level<D> level;
            level.lattice = std::make_shared<SimplexLattice<D>>(SimplexLattice<D>::dense(l));
            level.shape1 = shape1;
            level.shape2 = shape2;
            return level;
        };
    }

    /// Adaptive lattices: cells of side h within bandCells * h of M1 or M2, coarsest cells of
    /// side 2^-3, each level nested in the previous one (buildAdaptiveLattice with coarser).
    LevelBuilder<D> adaptiveLevels(Real bandCells) const
    {
        auto previous = std::make_shared<std::shared_ptr<const SimplexLattice<D>>>();
        return [this, previous, bandCells](int l) {
            const Real band = bandCells / Real(1 << l);
            const auto& s = shapes;
            const RefinementPredicate<D> nearShapes = [&s, band](const Vec<D>& x, Real radius) {
                const Real d1 = (x - s.center1).norm() - s.radius1;
                return std::abs(d1) < band + radius ||
                       std::abs(s.ellipse.signedDistance(x)) < band + radius;
            };
            const SimplexLattice<D>* coarser =
                *previous && (*previous)->level() == l - 1 ? previous->get() : nullptr;
            Level<D> level;
            level.lattice = std::make_shared<SimplexLattice<D>>(
                buildAdaptiveLattice<D>(l, std::max(0, l - 3), nearShapes, coarser));
            level.shape1 = shape1;
            level.shape2 = shape2;
            *previous = level.lattice;
            return level;
        };
    }

    /// Mean and max of |d2(phi(v))| over points v on M1 (analytic distance to M2).
    std::pair<Real, Real> residual(const SimplexLattice<D>& lattice, const NodeVectors<D>& u) const
    {
        const PiecewiseLinearInterpolator<D> interpolator(lattice);
        Real sum = 0, maxAbs = 0;
        const auto pts = shapes.pointsOnM1();
        for (const Vec<D>& v : pts) {
            Vec<D> uv;
            EXPECT_TRUE(interpolator.evaluate(u, v, uv));
            const Real d = std::abs(shapes.ellipse.signedDistance(v + uv));
            sum += d;
            maxAbs = std::max(maxAbs, d);
        }
        return {sum / Real(pts.size()), maxAbs};
    }
};

/// Records the energies per level and checks them as they come.
struct EnergyLog
{
    std::map<int, std::vector<Real>> energies;
    void operator()(const IterationInfo& info)
    {
        EXPECT_TRUE(std::isfinite(info.energy)) << "level " << info.level;
        auto& e = energies[info.level];
        EXPECT_EQ(std::size_t(info.iteration), e.size());
        if (!e.empty()) {
            EXPECT_LE(info.energy, e.back()) << "level " << info.level;
        }
        e.push_back(info.energy);
    }
};

template <int D>
void
checkMultiscaleMatch(const MultiscaleOptions& opts)
{
    const auto start = std::chrono::steady_clock::now();
    Problem<D> problem(opts.energy);
    EnergyLog log;
    const MultiscaleDriver<D> driver(opts);
    const MultiscaleResult<D> result =
        driver.run(problem.denseLevels(), [&](const IterationInfo& i) { log(i); });

    ASSERT_TRUE(result.isComplete());
    ASSERT_EQ(result.reports.size(), std::size_t(opts.maxLevel - opts.minLevel + 1));
    for (const Report& r : result.reports) {
        // Energies non-increasing within the level (checked by the log); every simplex keeps
        // det D phi > 0: finite energy at every iterate, including the prolongated initial guess
        // (iteration 0), and a positive minimum at the end.
        EXPECT_EQ(r.status, Status::Converged) << "level " << r.level;
        EXPECT_GT(r.minJacobian, 0.0) << "level " << r.level;
        EXPECT_LE(r.energy, r.initialEnergy);
        EXPECT_EQ(log.energies[r.level].size(), std::size_t(r.iterations) + 1);
        std::printf("[ level %d ] %s (%s), %d iterations, %zu + %zu evaluations, E %.6e -> "
                    "%.6e, |g| %.3e -> %.3e, min det %.3f, %.2f s\n",
                    r.level, toString(r.status), toString(r.convergedBy), r.iterations,
                    r.energyEvaluations, r.gradientEvaluations, r.initialEnergy, r.energy,
                    r.initialGradNorm, r.gradNorm, r.minJacobian, r.elapsedSeconds);
    }

    const SimplexLattice<D>& finest = *result.lattice;
    const auto [mean, maxAbs] = problem.residual(finest, result.displacement);
    std::printf("[ residual ] mean |d2(phi(v))| = %.3e, max %.3e, h/2 = %.3e\n", mean, maxAbs,
                finest.h() / 2);
    EXPECT_LT(mean, finest.h() / 2);

    // The symmetric energy at the result is below its value at the identity.
    const Energy<D> energy(finest, *problem.shape1, *problem.shape2, opts.energy,
                           EnergyKind::Symmetric);
    const Real atIdentity = energy.value(NodeVectors<D>::Zero(D, finest.nodeCount()));
    const Real atResult = energy.value(result.displacement);
    EXPECT_LT(atResult, atIdentity);
    EXPECT_NEAR(atResult, result.reports.back().energy, 1e-12 * atResult);
    std::printf("[ energy ] identity %.6e, result %.6e; total %.2f s\n", atIdentity, atResult,
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
}

/// Fires when told to.
class FlagInterrupter : public openvdb::util::NullInterrupter
{
public:
    bool wasInterrupted(int = -1) override { return mFired; }
    void fire() { mFired = true; }

private:
    bool mFired = false;
};

/// 2D defaults at levels @a first..@a last without descent steps: every level reports its terms
/// at the prolongated identity, so runs that differ in a weight differ only in that term.
MultiscaleOptions
noStepOptions(int first, int last)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = first;
    opts.maxLevel = last;
    opts.descent.maxIterations = 0;
    return opts;
}

/// Level by level, @a b's term @a scaled is @a scale[i] times @a a's (both halves, to 1e-12) and
/// the other three terms are bitwise @a a's: two runs without descent steps that differ in one
/// weight of one term.
void
expectOnlyTermScaled(const MultiscaleResult<2>& a, const MultiscaleResult<2>& b,
                     Real (EnergyTerms::*scaled)[2], const std::vector<Real>& scale)
{
    ASSERT_EQ(a.reports.size(), scale.size());
    ASSERT_EQ(b.reports.size(), scale.size());
    const std::array<Real(EnergyTerms::*)[2], 4> terms = {&EnergyTerms::match, &EnergyTerms::mem,
                                                          &EnergyTerms::bend, &EnergyTerms::vol};
    for (std::size_t i = 0; i < scale.size(); ++i) {
        const EnergyTerms &x = a.reports[i].terms, &y = b.reports[i].terms;
        for (const auto term : terms) {
            for (int k = 0; k < 2; ++k) {
                const Real u = (x.*term)[k], v = (y.*term)[k];
                if (term != scaled) {
                    EXPECT_EQ(v, u) << "level index " << i;
                    continue;
                }
                ASSERT_GT(u, 0.0);
                EXPECT_NEAR(v, scale[i] * u, 1e-12 * std::max(u, v)) << "level index " << i;
            }
        }
    }
}

} // namespace

TEST(Descent, SurfaceTestAppliesAtTheLastLevelsAndFromALevelOn)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(3);
    opts.minLevel = 4;
    opts.maxLevel = 8;
    auto levels = [&] {
        std::vector<int> at;
        for (int l = opts.minLevel; l <= opts.maxLevel; ++l)
            if (opts.surfaceTestAt(l)) at.push_back(l);
        return at;
    };
    opts.surfaceLevels = 1;
    opts.surfaceFromLevel = 0;
    EXPECT_EQ(levels(), std::vector<int>({8}));
    opts.surfaceFromLevel = 7;
    EXPECT_EQ(levels(), std::vector<int>({7, 8}));
    opts.surfaceFromLevel = 9; // beyond the finest: the last surfaceLevels still apply
    EXPECT_EQ(levels(), std::vector<int>({8}));
    opts.surfaceLevels = 0;
    EXPECT_TRUE(levels().empty());
    opts.surfaceFromLevel = 6;
    EXPECT_EQ(levels(), std::vector<int>({6, 7, 8}));
    opts.surfaceLevels = 3;
    opts.surfaceFromLevel = 0;
    EXPECT_EQ(levels(), std::vector<int>({6, 7, 8}));
    opts.surfaceFromLevel = -1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, CircleToEllipse2D)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = 4;
    opts.maxLevel = 6;
    checkMultiscaleMatch<2>(opts);
}

TEST(Descent, CircleToEllipse2DLimitedMemoryBfgs)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = 4;
    opts.maxLevel = 6;
    opts.descent.method = DescentMethod::LBFGS;
    checkMultiscaleMatch<2>(opts);
}

TEST(Descent, ParsesMethods)
{
    EXPECT_EQ(parseDescentMethod("ncg"), DescentMethod::NonlinearCG);
    EXPECT_EQ(parseDescentMethod("lbfgs"), DescentMethod::LBFGS);
    EXPECT_STREQ(toString(DescentMethod::LBFGS), "lbfgs");
    EXPECT_THROW(parseDescentMethod("newton"), openvdb::ValueError);
    DescentOptions opts;
    opts.lbfgsMemory = 0;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, SphereToEllipsoid3D)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(3);
    opts.minLevel = 3;
    opts.maxLevel = 5;
    // Looser than the default stagnation test (1e-5) to keep the test short: the residual is
    // already ~3e-3 h at this tolerance.
    opts.descent.energyTolerance = 1e-4;
    checkMultiscaleMatch<3>(opts);
}

TEST(Descent, CircleToEllipseAdaptive2D)
{
    // Levels 4..6 on adaptive lattices (side h within 6h of either shape) against the dense
    // run: every level descends, det D phi > 0, the matching residual is comparable.
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = 4;
    opts.maxLevel = 6;
    Problem<2> problem(opts.energy);
    const MultiscaleDriver<2> driver(opts);
    Real meanResidual[2] = {0, 0};
    std::size_t unknowns[2] = {0, 0};
    for (int adaptive = 0; adaptive < 2; ++adaptive) {
        EnergyLog log;
        const auto start = std::chrono::steady_clock::now();
        const MultiscaleResult<2> result =
            driver.run(adaptive ? problem.adaptiveLevels(6) : problem.denseLevels(),
                       [&](const IterationInfo& i) { log(i); });
        ASSERT_TRUE(result.isComplete());
        for (const Report& r : result.reports) {
            EXPECT_GT(r.minJacobian, 0.0) << "level " << r.level;
            EXPECT_LT(r.energy, r.initialEnergy) << "level " << r.level;
            EXPECT_NE(r.status, Status::LineSearchFailed) << "level " << r.level;
        }
        const Report& last = result.reports.back();
        meanResidual[adaptive] = problem.residual(*result.lattice, result.displacement).first;
        unknowns[adaptive] = result.lattice->freeNodeCount();
        // The result is continuous: the hanging nodes hold their constraint values.
        NodeVectors<2> expanded = result.displacement;
        result.lattice->expand(expanded);
        EXPECT_LT((expanded - result.displacement).cwiseAbs().maxCoeff(), 1e-15);
        std::printf(
            "[ %s ] level 6: %zu unknowns (%zu hanging), %d iterations, E %.6e, mean "
            "residual %.3e, min det %.3f, %.2f s\n",
            adaptive ? "adaptive" : "dense", unknowns[adaptive], result.lattice->hangingNodeCount(),
            last.iterations, last.energy, meanResidual[adaptive], last.minJacobian,
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    EXPECT_LT(unknowns[1], unknowns[0] * 3 / 4);
    EXPECT_LT(meanResidual[1], 2 * meanResidual[0] + 0.02 / 64);
}

TEST(Descent, CoarseMembraneFactorWeighsTheMembraneBelowTheFinestLevelOnly)
{
    // No descent steps: every level reports its terms at the prolongated identity, so the two
    // runs see the same deformations and differ only in the weights (MultiscaleOptions::energyAt).
    MultiscaleOptions opts = noStepOptions(4, 6);
    Problem<2> problem(opts.energy);
    const auto run = [&](Real factor) {
        MultiscaleOptions o = opts;
        o.coarseMembraneFactor = factor;
        return MultiscaleDriver<2>(o).run(problem.denseLevels());
    };
    // Levels 4 and 5: 3 c_mem; level 6: c_mem.
    expectOnlyTermScaled(run(1), run(3), &EnergyTerms::mem, {3.0, 3.0, 1.0});
    EXPECT_EQ(opts.energyAt(6).cMem, opts.energy.cMem);
    opts.coarseMembraneFactor = -1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.coarseMembraneFactor = std::numeric_limits<Real>::infinity();
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, LevelBendingFactorWeighsTheBendingTermOfItsLevelOnly)
{
    // Level::bendingFactor (match()'s noise-adaptive bending weight) multiplies c_bend at its
    // level and leaves the other terms and levels alone. No descent steps, as above.
    MultiscaleOptions opts = noStepOptions(4, 6);
    Problem<2> problem(opts.energy);
    const auto run = [&](Real factorAtLevel5) {
        const LevelBuilder<2> dense = problem.denseLevels();
        return MultiscaleDriver<2>(opts).run([&](int l) {
            Level<2> level = dense(l);
            if (l == 5) level.bendingFactor = factorAtLevel5;
            return level;
        });
    };
    expectOnlyTermScaled(run(1), run(0.25), &EnergyTerms::bend, {1.0, 0.25, 1.0});
    EXPECT_THROW(run(-0.5), openvdb::ValueError);
    EXPECT_THROW(run(1.5), openvdb::ValueError);
    EXPECT_THROW(run(std::numeric_limits<Real>::quiet_NaN()), openvdb::ValueError);
}

TEST(Descent, CoarseVolumeFactorWeighsTheVolumeBelowTheFinestLevelOnly)
{
    // At the identity the volume densities vanish (det D phi = 1), so the weights are checked
    // through energyAt, which the driver uses for every coefficient (the membrane test above).
    MultiscaleOptions opts = MultiscaleOptions::defaults(3);
    opts.minLevel = 4;
    opts.maxLevel = 7;
    opts.coarseVolumeFactor = 4;
    opts.coarseMembraneFactor = 3;
    for (int l = 4; l <= 7; ++l) {
        const EnergyParameters p = opts.energyAt(l);
        EXPECT_EQ(p.cVol, l < 7 ? 4 * opts.energy.cVol : opts.energy.cVol) << l;
        EXPECT_EQ(p.cMem, l < 7 ? 3 * opts.energy.cMem : opts.energy.cMem) << l;
        EXPECT_EQ(p.cMatch, opts.energy.cMatch) << l;
        EXPECT_EQ(p.cBend, opts.energy.cBend) << l;
    }
    EXPECT_EQ(MultiscaleOptions::defaults(2).coarseVolumeFactor, 1.0); // the paper's c_vol
    opts.coarseVolumeFactor = -1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.coarseVolumeFactor = std::numeric_limits<Real>::quiet_NaN();
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, CoarseSigmaFactorWidensTheBandBelowTheFinestLevelOnly)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    EXPECT_EQ(opts.coarseSigmaFactor, 1.0); // tab:parameters: sigma = 2h at every level
    opts.minLevel = 4;
    opts.maxLevel = 7;
    opts.coarseSigmaFactor = 1.5;
    for (int l = 4; l <= 7; ++l) {
        const EnergyParameters p = opts.energyAt(l);
        EXPECT_EQ(p.sigmaFactor, l < 7 ? 3.0 : 2.0) << l;
        EXPECT_EQ(p.cMatch, opts.energy.cMatch) << l;
        EXPECT_EQ(p.cVol, opts.energy.cVol) << l;
    }
    // The driver builds each level's energy from energyAt: without descent steps every level
    // starts and ends at the identity, where its energy is that of sigma = 3h below the finest
    // level (with the weights sigma^-q of eq:EsymMatch and sigma^theta of eq:EsymVol that
    // follow) and of the paper's sigma = 2h at the finest.
    opts.descent.maxIterations = 0;
    Problem<2> problem(opts.energy);
    const MultiscaleResult<2> result = MultiscaleDriver<2>(opts).run(problem.denseLevels());
    ASSERT_EQ(result.reports.size(), 4u);
    for (int l = 4; l <= 7; ++l) {
        const SimplexLattice<2> lattice = SimplexLattice<2>::dense(l);
        const NodeVectors<2> identity = NodeVectors<2>::Zero(2, lattice.nodeCount());
        const auto energyWith = [&](Real sigmaFactor) {
            EnergyParameters p = opts.energy;
            p.sigmaFactor = sigmaFactor;
            return Energy<2>(lattice, *problem.shape1, *problem.shape2, p, opts.kind)
                .value(identity);
        };
        const Real wide = energyWith(3), paper = energyWith(2);
        ASSERT_NE(wide, paper) << l;
        EXPECT_EQ(result.reports[std::size_t(l - 4)].initialEnergy, l < 7 ? wide : paper) << l;
    }
    for (const Real bad : {0.25, 3.5, std::numeric_limits<Real>::quiet_NaN()}) {
        opts.coarseSigmaFactor = bad;
        EXPECT_THROW(opts.validate(), openvdb::ValueError) << bad;
    }
}

TEST(Descent, MembraneSaturationActsAtTheFirstLevelsOnly)
{
    // As above: no descent steps, so the runs differ only in the energy of each level.
    MultiscaleOptions opts = noStepOptions(4, 7);
    EXPECT_EQ(opts.energy.membraneSaturation, 0.0); // tab:parameters: the paper's W
    Problem<2> problem(opts.energy);
    const auto run = [&](Real s, int levels) {
        MultiscaleOptions o = opts;
        o.energy.membraneSaturation = s;
        o.membraneSaturationLevels = levels;
        return MultiscaleDriver<2>(o).run(problem.denseLevels());
    };
    const MultiscaleResult<2> paper = run(0, 2), saturated = run(0.001, 2), all = run(0.001, 9);
    ASSERT_EQ(saturated.reports.size(), 4u);
    for (std::size_t i = 0; i < 4; ++i) {
        const EnergyTerms &a = paper.reports[i].terms, &b = saturated.reports[i].terms,
                          &c = all.reports[i].terms;
        for (int k = 0; k < 2; ++k) {
            ASSERT_GT(a.mem[k], 0.0);
            if (i < 2) // levels 4 and 5: saturated
                EXPECT_LT(b.mem[k], a.mem[k]) << i;
            else // levels 6 and 7: the paper's W, bit for bit
                EXPECT_EQ(b.mem[k], a.mem[k]) << i;
            EXPECT_LT(c.mem[k], a.mem[k]) << i;
            EXPECT_EQ(b.match[k], a.match[k]) << i;
            EXPECT_EQ(b.bend[k], a.bend[k]) << i;
        }
    }
    opts.energy.membraneSaturation = 0.1;
    EXPECT_EQ(opts.energyAt(5).membraneSaturation, 0.1);
    EXPECT_EQ(opts.energyAt(6).membraneSaturation, 0.0);
    opts.membraneSaturationLevels = -1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.membraneSaturationLevels = 2;
    opts.energy.membraneSaturation = -0.1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.energy.membraneSaturation = std::numeric_limits<Real>::quiet_NaN();
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, InterrupterStopsTheRun)
{
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = 4;
    opts.maxLevel = 6;
    Problem<2> problem(opts.energy);
    FlagInterrupter interrupter;
    int lastIteration = -1;
    const MultiscaleDriver<2> driver(opts);
    const MultiscaleResult<2> result = driver.run(
        problem.denseLevels(),
        [&](const IterationInfo& info) {
            lastIteration = info.iteration;
            if (info.level == 5 && info.iteration == 3) interrupter.fire();
        },
        true, &interrupter);
    ASSERT_EQ(result.reports.size(), 2u);
    EXPECT_TRUE(result.isInterrupted());
    EXPECT_FALSE(result.isComplete());
    EXPECT_EQ(result.reports[0].status, Status::Converged);
    const Report& stopped = result.reports[1];
    EXPECT_EQ(stopped.status, Status::Interrupted);
    EXPECT_EQ(stopped.level, 5);
    EXPECT_EQ(stopped.iterations, 3);
    EXPECT_EQ(lastIteration, 3);
    // The displacement is the last accepted iterate of level 5: valid, with the reported energy.
    ASSERT_EQ(result.lattice->level(), 5);
    const Energy<2> energy(*result.lattice, *problem.shape1, *problem.shape2, opts.energy,
                           EnergyKind::Symmetric);
    EXPECT_DOUBLE_EQ(energy.value(result.displacement), stopped.energy);
    EXPECT_GT(energy.minJacobianDeterminant(result.displacement), 0.0);
}

TEST(Descent, MaxIterationsAndThreadCountIndependence)
{
    const EnergyParameters params = EnergyParameters::defaults(2);
    Problem<2> problem(params);
    const auto lattice = SimplexLattice<2>::dense(5);
    const Energy<2> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const H1Metric<2> metric(lattice, DEFAULT_METRIC_TAU_FACTOR * energy.sigma() * energy.sigma());
    DescentOptions opts;
    opts.maxIterations = 12;
    const Descent<2> descent(energy, metric, opts);
    NodeVectors<2> serial = NodeVectors<2>::Zero(2, lattice.nodeCount());
    NodeVectors<2> threaded = serial;
    const Report a = descent.run(serial, {}, false);
    const Report b = descent.run(threaded, {}, true);
    EXPECT_EQ(a.status, Status::MaxIterations);
    EXPECT_EQ(a.iterations, 12);
    EXPECT_LT(a.energy, a.initialEnergy);
    EXPECT_TRUE(serial == threaded);
    EXPECT_EQ(a.energy, b.energy);
    EXPECT_EQ(a.energyEvaluations, b.energyEvaluations);
    EXPECT_EQ(a.gradientEvaluations, b.gradientEvaluations);
}

namespace {

/// The line search's trials with gradients (DescentOptions::gradientAtTrials, the default) or
/// without: the same iterates to the last bit, with the accepted trial's gradient reused.
template <int D>
void
checkGradientsAtTrials(DescentMethod method, int level, int iterations)
{
    const EnergyParameters params = EnergyParameters::defaults(D);
    Problem<D> problem(params);
    const auto lattice = SimplexLattice<D>::dense(level);
    const Energy<D> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const H1Metric<D> metric(lattice, DEFAULT_METRIC_TAU_FACTOR * energy.sigma() * energy.sigma());
    DescentOptions opts;
    opts.method = method;
    opts.maxIterations = iterations;
    opts.energyTolerance = 0;
    opts.gradientAtTrials = true;
    const Descent<D> fused(energy, metric, opts);
    opts.gradientAtTrials = false;
    const Descent<D> separate(energy, metric, opts);
    NodeVectors<D> u1 = NodeVectors<D>::Zero(D, lattice.nodeCount());
    NodeVectors<D> u2 = u1;
    const Report a = fused.run(u1);
    const Report b = separate.run(u2);
    EXPECT_EQ(a.iterations, iterations);
    EXPECT_EQ(b.iterations, iterations);
    EXPECT_TRUE(u1 == u2);
    EXPECT_EQ(a.energy, b.energy);
    EXPECT_EQ(a.gradNorm, b.gradNorm);
    EXPECT_EQ(a.metricIterations, b.metricIterations);
    // Fused: every trial is a value-and-gradient evaluation, plus the initial one. Separate:
    // the trials are value-only, and a gradient follows each accepted step.
    EXPECT_EQ(a.energyEvaluations, 0u);
    EXPECT_EQ(a.gradientEvaluations, b.energyEvaluations + 1);
    EXPECT_EQ(b.gradientEvaluations, std::size_t(iterations) + 1);
    EXPECT_GE(b.energyEvaluations, std::size_t(iterations));
}

} // namespace

TEST(Descent, GradientsAtTrialsGiveTheSameIterates2D)
{
    checkGradientsAtTrials<2>(DescentMethod::NonlinearCG, 5, 40);
}
TEST(Descent, GradientsAtTrialsGiveTheSameIteratesLimitedMemoryBfgs2D)
{
    checkGradientsAtTrials<2>(DescentMethod::LBFGS, 5, 40);
}
TEST(Descent, GradientsAtTrialsGiveTheSameIterates3D)
{
    checkGradientsAtTrials<3>(DescentMethod::NonlinearCG, 3, 15);
}

TEST(Descent, IdenticalShapesStayAtIdentity)
{
    const EnergyParameters params = EnergyParameters::defaults(2);
    Problem<2> problem(params);
    const auto lattice = SimplexLattice<2>::dense(5);
    const Energy<2> energy(lattice, *problem.shape1, *problem.shape1, params,
                           EnergyKind::Symmetric);
    const H1Metric<2> metric(lattice, DEFAULT_METRIC_TAU_FACTOR * energy.sigma() * energy.sigma());
    const Descent<2> descent(energy, metric);
    NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
    const Report r = descent.run(u);
    std::printf("[ identical ] %s (%s), %d iterations, |g| %.3e -> %.3e, max |u| %.3e\n",
                toString(r.status), toString(r.convergedBy), r.iterations, r.initialGradNorm,
                r.gradNorm, u.cwiseAbs().maxCoeff());
    EXPECT_NE(r.status, Status::Interrupted);
    EXPECT_NE(r.status, Status::MaxIterations);
    EXPECT_LE(r.energy, r.initialEnergy);
    EXPECT_LT(u.cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Descent, InvertedInitialGuessThrows)
{
    const EnergyParameters params = EnergyParameters::defaults(2);
    Problem<2> problem(params);
    const auto lattice = SimplexLattice<2>::dense(4);
    const Energy<2> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const H1Metric<2> metric(lattice, 0.0);
    const Descent<2> descent(energy, metric);
    NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
    // Push one interior node across its neighbour: its simplices invert.
    const int32_t i = lattice.findNode(openvdb::Coord(8, 8, 0));
    u(0, i) = 1.5 * lattice.h();
    EXPECT_THROW(descent.run(u), openvdb::ValueError);
}

// ---------------------------------------------------------------- Armijo backtracking

TEST(ArmijoLineSearch, AcceptsSufficientDecrease)
{
    // E(t) = (t - 1)^2: E0 = 1, slope -2; from t0 = 8 the search halves to t <= 2 (1 - 2 c1).
    ArmijoOptions opts;
    opts.interpolate = false;
    const TrialEnergy quadratic = [](Real t, EnergyTerms&, bool& evaluated) {
        evaluated = true;
        return (t - 1) * (t - 1);
    };
    LineSearchResult r = armijoBacktrack(quadratic, 1.0, -2.0, 8.0, 1.0, opts);
    ASSERT_TRUE(r.isAccepted());
    EXPECT_EQ(r.step, 1.0); // 8, 4, 2 (E = 1 > 1 - 4e-4), 1
    EXPECT_EQ(r.evaluations, 4);
    EXPECT_LE(r.energy, 1.0 + opts.c1 * r.step * -2.0);

    // Interpolation jumps to the minimiser of the quadratic.
    opts.interpolate = true;
    r = armijoBacktrack(quadratic, 1.0, -2.0, 8.0, 1.0, opts);
    ASSERT_TRUE(r.isAccepted());
    EXPECT_DOUBLE_EQ(r.step, 1.0);
    EXPECT_EQ(r.evaluations, 2);
}

TEST(ArmijoLineSearch, RejectsInfiniteEnergy)
{
    // +inf beyond t = 0.3 (an inverted simplex): the step backtracks below it, no NaN.
    const TrialEnergy barrier = [](Real t, EnergyTerms&, bool& evaluated) {
        evaluated = true;
        return t > 0.3 ? INF : -t;
    };
    const LineSearchResult r = armijoBacktrack(barrier, 0.0, -1.0, 1.0, 1.0, ArmijoOptions{});
    ASSERT_TRUE(r.isAccepted());
    EXPECT_EQ(r.step, 0.25);
    EXPECT_EQ(r.rejectedInfinite, 2);
}

TEST(ArmijoLineSearch, FailureOutcomes)
{
    const TrialEnergy increasing = [](Real t, EnergyTerms&, bool& evaluated) {
        evaluated = true;
        return t;
    };
    ArmijoOptions opts;
    // Not a descent direction: nothing evaluated.
    LineSearchResult r = armijoBacktrack(increasing, 0.0, 1.0, 1.0, 1.0, opts);
    EXPECT_EQ(r.status, LineSearchStatus::NotDescentDirection);
    EXPECT_EQ(r.evaluations, 0);
    // No decrease anywhere: the step underflows.
    opts.interpolate = false;
    r = armijoBacktrack(increasing, 0.0, -1.0, 1.0, 1.0, opts);
    EXPECT_EQ(r.status, LineSearchStatus::StepUnderflow);
    EXPECT_EQ(r.evaluations, 44); // t = 2^0 .. 2^-43 (1.1e-13 >= 1e-13 > 2^-44)
    // Evaluation budget.
    opts.maxEvaluations = 5;
    r = armijoBacktrack(increasing, 0.0, -1.0, 1.0, 1.0, opts);
    EXPECT_EQ(r.status, LineSearchStatus::TooManyEvaluations);
    EXPECT_EQ(r.evaluations, 5);
    // Cancellation: an infinite energy while the interrupter fires.
    FlagInterrupter interrupter;
    interrupter.fire();
    const TrialEnergy cancelled = [](Real, EnergyTerms&, bool& evaluated) {
        evaluated = true;
        return INF;
    };
    r = armijoBacktrack(cancelled, 0.0, -1.0, 1.0, 1.0, ArmijoOptions{}, &interrupter);
    EXPECT_EQ(r.status, LineSearchStatus::Interrupted);
    EXPECT_THROW(ArmijoLineSearch<2>(ArmijoOptions{2.0}), openvdb::ValueError);
}

TEST(Descent, SettleTestEndsALevelOnRelativeProgress)
{
    // The settle test (DescentOptions::settleTolerance) ends the run when the last w iterations
    // gained less than a fraction of what the run gained so far. Checked against the energy
    // history the observer sees, and a tighter tolerance runs longer to a lower energy.
    const EnergyParameters params = EnergyParameters::defaults(2);
    Problem<2> problem(params);
    const auto lattice = SimplexLattice<2>::dense(5);
    const Energy<2> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const H1Metric<2> metric(lattice, DEFAULT_METRIC_TAU_FACTOR * energy.sigma() * energy.sigma());
    Report reports[2];
    for (int k = 0; k < 2; ++k) {
        DescentOptions opts;
        opts.energyTolerance = 0;
        opts.relativeGradientTolerance = 0;
        opts.settleTolerance = k == 0 ? 3e-2 : 3e-3;
        std::vector<Real> history;
        const Descent<2> descent(energy, metric, opts);
        NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
        reports[k] = descent.run(u, [&](const IterationInfo& i) { history.push_back(i.energy); });
        const Report& r = reports[k];
        ASSERT_EQ(r.status, Status::Converged);
        EXPECT_EQ(r.convergedBy, ConvergenceTest::Settled);
        const std::size_t w = std::size_t(opts.energyWindow);
        ASSERT_EQ(history.size(), std::size_t(r.iterations) + 1);
        ASSERT_GT(history.size(), w);
        // The test holds at the last iteration and at no earlier one.
        auto settled = [&](std::size_t j) {
            return history[j - w] - history[j] <= opts.settleTolerance * (history[0] - history[j]);
        };
        EXPECT_TRUE(settled(history.size() - 1));
        for (std::size_t j = w; j + 1 < history.size(); ++j)
            EXPECT_FALSE(settled(j)) << "iteration " << j;
    }
    EXPECT_GT(reports[1].iterations, reports[0].iterations);
    EXPECT_LT(reports[1].energy, reports[0].energy);
    EXPECT_STREQ(toString(ConvergenceTest::Settled), "settled");
}

TEST(Descent, IterationCoarseningRaisesTheLimitBelowTheFinestLevel)
{
    // MultiscaleOptions::iterationCoarsening (match()'s default 2, an addition to the paper):
    // level l may run maxIterations * F^(maxLevel - l) iterations.
    MultiscaleOptions opts = MultiscaleOptions::defaults(2);
    opts.minLevel = 4;
    opts.maxLevel = 8;
    opts.descent.maxIterations = 500;
    EXPECT_EQ(levelIterationLimit(opts, 8), 500); // F = 1, the paper: one limit
    EXPECT_EQ(levelIterationLimit(opts, 4), 500);
    opts.iterationCoarsening = 2;
    EXPECT_EQ(levelIterationLimit(opts, 8), 500);
    EXPECT_EQ(levelIterationLimit(opts, 7), 1000);
    EXPECT_EQ(levelIterationLimit(opts, 4), 8000);
    opts.iterationCoarsening = 1e6;
    EXPECT_EQ(levelIterationLimit(opts, 4), MAX_LEVEL_ITERATIONS);
    opts.descent.maxIterations = 0; // no descent stays no descent
    EXPECT_EQ(levelIterationLimit(opts, 4), 0);

    // A run of the circle onto the ellipse that no level finishes in 2 iterations: each level
    // stops at its own limit, 8, 4, 2.
    opts.minLevel = 4;
    opts.maxLevel = 6;
    opts.descent.maxIterations = 2;
    opts.iterationCoarsening = 2;
    Problem<2> problem(opts.energy);
    const MultiscaleResult<2> result = MultiscaleDriver<2>(opts).run(problem.denseLevels());
    ASSERT_EQ(result.reports.size(), 3u);
    const int expected[3] = {8, 4, 2};
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(result.reports[std::size_t(k)].status, Status::MaxIterations)
            << "level " << 4 + k;
        EXPECT_EQ(result.reports[std::size_t(k)].iterations, expected[k]) << "level " << 4 + k;
    }
    opts.iterationCoarsening = 0.5;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.iterationCoarsening = std::numeric_limits<Real>::infinity();
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
}

TEST(Descent, RejectsInvalidSettleTolerance)
{
    DescentOptions opts;
    opts.settleTolerance = -1;
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    opts.settleTolerance = std::numeric_limits<Real>::infinity();
    EXPECT_THROW(opts.validate(), openvdb::ValueError);
    MultiscaleOptions m = MultiscaleOptions::defaults(2);
    m.toleranceCoarsening = 0.5;
    EXPECT_THROW(m.validate(), openvdb::ValueError);
}

namespace {

/// The probe of the points on M1 on @a lattice (every point lies in a cell of a dense lattice).
SurfaceProbe<2>
probeOnM1(const SimplexLattice<2>& lattice, const std::vector<Vec<2>>& points)
{
    const PiecewiseLinearInterpolator<2> locator(lattice);
    PiecewiseLinearInterpolator<2>::Location loc;
    SurfaceProbe<2> probe;
    for (const Vec<2>& x : points)
        if (locator.locate(x, loc)) probe.add(loc.nodes, loc.weights);
    return probe;
}

} // namespace

TEST(SurfaceProbe, EqualsThePiecewiseLinearInterpolant)
{
    // The probe's displacements are the P1 interpolant of u at the points, as evaluated by
    // PiecewiseLinearInterpolator, for an arbitrary nodal field.
    const auto lattice = SimplexLattice<2>::dense(4);
    const std::vector<Vec<2>> points = Shapes<2>().pointsOnM1();
    const SurfaceProbe<2> probe = probeOnM1(lattice, points);
    ASSERT_EQ(probe.size(), points.size());
    NodeVectors<2> u(2, lattice.nodeCount());
    for (Eigen::Index i = 0; i < u.cols(); ++i)
        u.col(i) = Vec<2>(std::sin(3.0 * Real(i)), std::cos(5.0 * Real(i))) * 1e-2;
    NodeVectors<2> atPoints;
    probe.displacements(u, atPoints);
    const PiecewiseLinearInterpolator<2> phi(lattice);
    for (std::size_t k = 0; k < points.size(); ++k) {
        Vec<2> expected;
        ASSERT_TRUE(phi.evaluate(u, points[k], expected));
        EXPECT_NEAR((atPoints.col(Eigen::Index(k)) - expected).norm(), 0.0, 1e-15) << k;
    }
    NodeVectors<2> shifted = atPoints;
    shifted.row(0).array() += 3e-3;
    EXPECT_NEAR(SurfaceProbe<2>::meanDistance(shifted, atPoints), 3e-3, 1e-15);
}

TEST(Descent, SurfaceTestEndsALevelWhenTheSurfaceStopsMoving)
{
    // The surface test (DescentOptions::surfaceTolerance) ends the run when phi on M1 moved by
    // less than the tolerance over the last w iterations (path length). It holds at the last
    // iteration and at no earlier one, it stops before the energy test, and the surface it
    // stops at is within a small fraction of h of the one the energy test reaches: what the
    // iterations it saves would have changed on M1.
    const EnergyParameters params = EnergyParameters::defaults(2);
    Problem<2> problem(params);
    const auto lattice = SimplexLattice<2>::dense(5);
    const Real h = lattice.h();
    const Energy<2> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const H1Metric<2> metric(lattice, DEFAULT_METRIC_TAU_FACTOR * energy.sigma() * energy.sigma());
    const SurfaceProbe<2> probe = probeOnM1(lattice, problem.shapes.pointsOnM1());

    DescentOptions full;
    full.energyTolerance = 1e-6;
    DescentOptions settled = full;
    settled.surfaceTolerance = 0.02 * h;
    NodeVectors<2> surface[2];
    Report reports[2];
    for (int k = 0; k < 2; ++k) {
        const DescentOptions& opts = k == 0 ? full : settled;
        Descent<2> descent(energy, metric, opts);
        descent.setSurfaceProbe(&probe);
        std::vector<Real> motion;
        NodeVectors<2> u = NodeVectors<2>::Zero(2, lattice.nodeCount());
        reports[k] =
            descent.run(u, [&](const IterationInfo& i) { motion.push_back(i.surfaceMotion); });
        ASSERT_EQ(reports[k].status, Status::Converged);
        probe.displacements(u, surface[k]);
        const std::size_t w = std::size_t(opts.energyWindow);
        ASSERT_EQ(motion.size(), std::size_t(reports[k].iterations) + 1);
        for (std::size_t j = 0; j < motion.size(); ++j) {
            // Reported from the w-th iteration on, as a path length (>= 0).
            if (j < w)
                EXPECT_LT(motion[j], 0) << j;
            else
                EXPECT_GE(motion[j], 0) << j;
        }
        if (k == 1) {
            EXPECT_EQ(reports[k].convergedBy, ConvergenceTest::SurfaceSettled);
            EXPECT_LE(motion.back(), settled.surfaceTolerance);
            for (std::size_t j = w; j + 1 < motion.size(); ++j)
                EXPECT_GT(motion[j], settled.surfaceTolerance) << "iteration " << j;
        } else {
            EXPECT_NE(reports[k].convergedBy, ConvergenceTest::SurfaceSettled);
        }
    }
    std::printf("[ surface test ] %d iterations (energy test: %d), E %.6e (%.6e), surface "
                "%.3e h from the energy test's\n",
                reports[1].iterations, reports[0].iterations, reports[1].energy, reports[0].energy,
                SurfaceProbe<2>::meanDistance(surface[1], surface[0]) / h);
    EXPECT_LT(2 * reports[1].iterations, reports[0].iterations);
    EXPECT_LT(SurfaceProbe<2>::meanDistance(surface[1], surface[0]), 0.1 * h);
    EXPECT_STREQ(toString(ConvergenceTest::SurfaceSettled), "surface settled");

    DescentOptions invalid;
    invalid.surfaceTolerance = -1;
    EXPECT_THROW(invalid.validate(), openvdb::ValueError);
    MultiscaleOptions m = MultiscaleOptions::defaults(2);
    m.surfaceTolerance = std::numeric_limits<Real>::quiet_NaN();
    EXPECT_THROW(m.validate(), openvdb::ValueError);
}
