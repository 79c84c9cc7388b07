/// @file BenchEnergy.cc
/// @brief Throughput of the symmetric energy with gradient (simplices per second per thread) on
///        a 3D band around a sphere at h = 1/256, the 1 -> 2 thread speed-up, the value-only and
///        directional variants, the time to build the geometry fields, and the H^1 metric of the
///        descent (building it, and one solve G^{-1} g at the match's CG tolerance).
///
/// Run: build/bench/vdbmatch_bench_energy  (figures and their reading in docs/performance.md)
#include "support/AnalyticShapes.h"

#include <vdbmatch/Match.h>
#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/solver/H1Metric.h>

#include <benchmark/benchmark.h>
#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <memory>
#include <random>

using namespace vdbmatch;

namespace {

constexpr int LEVEL = 8;         ///< h = 1/256
constexpr Real RADIUS1 = 0.3;    ///< M1: sphere at the centre
constexpr Real RADIUS2 = 0.302;  ///< M2: slightly larger, shifted sphere
constexpr Real BAND_VOXELS = 12; ///< half-width of the signed-distance grids, voxels

struct BandProblem
{
    openvdb::FloatGrid::Ptr sdf1, sdf2;
    std::unique_ptr<SimplexLattice<3>> lattice;
    FieldSampler<3>::Ptr shape1, shape2;
    NodeVectors<3> u;

    BandProblem()
    {
        openvdb::initialize();
        const Vec<3> c1(0.5, 0.5, 0.5), c2(0.501, 0.499, 0.5);
        sdf1 = test::createSdfGrid<3>(
            LEVEL, [&](const Vec<3>& x) { return (x - c1).norm() - RADIUS1; },
            test::DEFAULT_GRID_MARGIN, BAND_VOXELS);
        sdf2 = test::createSdfGrid<3>(
            LEVEL, [&](const Vec<3>& x) { return (x - c2).norm() - RADIUS2; },
            test::DEFAULT_GRID_MARGIN, BAND_VOXELS);
        // Cells: the band |d1| < 3h around M1 (where the direct terms live).
        const Real h = 1.0 / (1 << LEVEL);
        auto cells = openvdb::MaskGrid::create(false);
        auto acc = cells->getAccessor();
        for (auto it = sdf1->cbeginValueOn(); it; ++it)
            if (std::abs(*it) < 3 * h) acc.setValueOn(it.getCoord());
        lattice =
            std::make_unique<SimplexLattice<3>>(SimplexLattice<3>::fromCellMasks(LEVEL, {cells}));
        ShapeFieldOptions opts;
        shape1 = FieldSampler<3>::build({sdf1}, opts);
        shape2 = FieldSampler<3>::build({sdf2}, opts);
        std::mt19937 rng(3);
        std::uniform_real_distribution<Real> U(-0.2 * h, 0.2 * h);
        u.resize(3, lattice->nodeCount());
        for (Eigen::Index i = 0; i < u.size(); ++i)
            u.data()[i] = U(rng);
    }
};

BandProblem&
problem()
{
    static BandProblem p;
    return p;
}

void
BM_SymmetricValueAndGradient(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    Energy<3> E(*P.lattice, *P.shape1, *P.shape2, EnergyParameters::defaults(3),
                EnergyKind::Symmetric);
    NodeVectors<3> g;
    EnergyTerms t;
    for (auto _ : state)
        benchmark::DoNotOptimize(E.valueAndGradient(P.u, g, &t));
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(P.lattice->simplexCount()));
    state.counters["simplices"] = double(P.lattice->simplexCount());
    state.counters["band_simplices"] = double(t.bandSimplices);
    state.counters["simplices_per_s_per_thread"] =
        benchmark::Counter(double(P.lattice->simplexCount()) / double(state.range(0)),
                           benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SymmetricValueAndGradient)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void
BM_SymmetricValue(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    Energy<3> E(*P.lattice, *P.shape1, *P.shape2, EnergyParameters::defaults(3),
                EnergyKind::Symmetric);
    for (auto _ : state)
        benchmark::DoNotOptimize(E.value(P.u));
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(P.lattice->simplexCount()));
    state.counters["simplices_per_s_per_thread"] =
        benchmark::Counter(double(P.lattice->simplexCount()) / double(state.range(0)),
                           benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_SymmetricValue)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void
BM_DirectionalValueAndGradient(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    Energy<3> E(*P.lattice, *P.shape1, *P.shape2, EnergyParameters::defaults(3),
                EnergyKind::Directional);
    NodeVectors<3> g;
    for (auto _ : state)
        benchmark::DoNotOptimize(E.valueAndGradient(P.u, g));
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(P.lattice->simplexCount()));
    state.counters["simplices_per_s_per_thread"] =
        benchmark::Counter(double(P.lattice->simplexCount()) / double(state.range(0)),
                           benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_DirectionalValueAndGradient)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void
BM_BuildFields(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    ShapeFieldOptions opts;
    for (auto _ : state)
        benchmark::DoNotOptimize(FieldSampler<3>::build({P.sdf1}, opts));
    state.counters["sdf_voxels"] = double(P.sdf1->activeVoxelCount());
}
BENCHMARK(BM_BuildFields)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void
BM_BuildLattice(benchmark::State& state)
{
    auto& P = problem();
    const Real h = 1.0 / (1 << LEVEL);
    auto cells = openvdb::MaskGrid::create(false);
    auto acc = cells->getAccessor();
    for (auto it = P.sdf1->cbeginValueOn(); it; ++it)
        if (std::abs(*it) < 3 * h) acc.setValueOn(it.getCoord());
    for (auto _ : state)
        benchmark::DoNotOptimize(SimplexLattice<3>::fromCellMasks(LEVEL, {cells}).nodeCount());
}
BENCHMARK(BM_BuildLattice)->Unit(benchmark::kMillisecond)->UseRealTime();

/// tau of the match at this level: DEFAULT_METRIC_TAU_FACTOR sigma^2, sigma = 2h.
Real
metricTau()
{
    const Real sigma = 2.0 / (1 << LEVEL);
    return solver::DEFAULT_METRIC_TAU_FACTOR * sigma * sigma;
}

/// The match's CG options (the metric of a 3D band of this size is never factorised).
solver::H1MetricOptions
matchMetricOptions()
{
    solver::H1MetricOptions opts;
    opts.method = solver::H1MetricOptions::Method::ConjugateGradient;
    opts.cgTolerance = DEFAULT_MATCH_METRIC_TOLERANCE;
    return opts;
}

void
BM_MetricBuild(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    for (auto _ : state)
        benchmark::DoNotOptimize(
            solver::H1Metric<3>(*P.lattice, metricTau(), matchMetricOptions()).unknownCount());
}
BENCHMARK(BM_MetricBuild)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void
BM_MetricSolve(benchmark::State& state)
{
    auto& P = problem();
    tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(0));
    const solver::H1Metric<3> metric(*P.lattice, metricTau(), matchMetricOptions());
    Energy<3> E(*P.lattice, *P.shape1, *P.shape2, EnergyParameters::defaults(3),
                EnergyKind::Symmetric);
    NodeVectors<3> g, r;
    E.valueAndGradient(P.u, g);
    metric.zeroDirichlet(g);
    int iterations = 0;
    for (auto _ : state)
        iterations = metric.applyInverse(g, r).iterations;
    state.counters["unknowns"] = double(metric.unknownCount());
    state.counters["cg_iterations"] = double(iterations);
}
BENCHMARK(BM_MetricSolve)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

} // namespace

BENCHMARK_MAIN();
