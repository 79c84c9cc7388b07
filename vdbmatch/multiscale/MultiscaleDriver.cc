/// @file MultiscaleDriver.cc
#include "MultiscaleDriver.h"

#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <optional>

namespace vdbmatch {
namespace multiscale {

MultiscaleOptions
MultiscaleOptions::defaults(int dim)
{
    MultiscaleOptions opts;
    opts.energy = EnergyParameters::defaults(dim);
    opts.minLevel = 4;
    opts.maxLevel = dim == 2 ? 9 : 8;
    return opts;
}

int
levelIterationLimit(const MultiscaleOptions& opts, int l)
{
    const int base = opts.descent.maxIterations;
    const double limit =
        std::round(double(base) * std::pow(double(opts.iterationCoarsening), opts.maxLevel - l));
    return std::max(base, int(std::min(limit, double(MAX_LEVEL_ITERATIONS))));
}

void
MultiscaleOptions::validate() const
{
    if (minLevel < 1 || maxLevel < minLevel)
        OPENVDB_THROW(openvdb::ValueError, "MultiscaleOptions: need 1 <= minLevel <= maxLevel, got "
                                               << minLevel << ", " << maxLevel);
    if (!(metricTauFactor >= 0) || !std::isfinite(metricTauFactor))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: metricTauFactor must be finite and >= 0, got "
                          << metricTauFactor);
    if (!(toleranceCoarsening >= 1) || !std::isfinite(toleranceCoarsening))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: toleranceCoarsening must be finite and >= 1, got "
                          << toleranceCoarsening);
    if (!(iterationCoarsening >= 1) || !std::isfinite(iterationCoarsening))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: iterationCoarsening must be finite and >= 1, got "
                          << iterationCoarsening);
    if (!(surfaceTolerance >= 0) || !std::isfinite(surfaceTolerance))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: surfaceTolerance must be finite and >= 0, got "
                          << surfaceTolerance);
    if (surfaceLevels < 0)
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: surfaceLevels must be >= 0, got " << surfaceLevels);
    if (surfaceFromLevel < 0)
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: surfaceFromLevel must be >= 0, got " << surfaceFromLevel);
    if (!(coarseMembraneFactor >= 0 && coarseMembraneFactor <= MAX_COEFFICIENT))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: coarseMembraneFactor must be finite and in [0, "
                          << MAX_COEFFICIENT << "], got " << coarseMembraneFactor);
    if (!(coarseVolumeFactor >= 0 && coarseVolumeFactor <= MAX_COEFFICIENT))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: coarseVolumeFactor must be finite and in [0, "
                          << MAX_COEFFICIENT << "], got " << coarseVolumeFactor);
    if (!(coarseSigmaFactor >= MIN_COARSE_SIGMA_FACTOR &&
          coarseSigmaFactor <= MAX_COARSE_SIGMA_FACTOR))
        OPENVDB_THROW(openvdb::ValueError, "MultiscaleOptions: coarseSigmaFactor must be in ["
                                               << MIN_COARSE_SIGMA_FACTOR << ", "
                                               << MAX_COARSE_SIGMA_FACTOR << "], got "
                                               << coarseSigmaFactor);
    if (membraneSaturationLevels < 0)
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: membraneSaturationLevels must be >= 0, got "
                          << membraneSaturationLevels);
    if (!(metric.cgTolerance > 0 && metric.cgTolerance < 1))
        OPENVDB_THROW(openvdb::ValueError,
                      "MultiscaleOptions: the metric tolerance must be in (0, 1), got "
                          << metric.cgTolerance);
    energy.validate();
    descent.validate();
}

EnergyParameters
MultiscaleOptions::energyAt(int level) const
{
    EnergyParameters p = energy;
    if (level < maxLevel) {
        p.cMem *= coarseMembraneFactor;
        p.cVol *= coarseVolumeFactor;
        p.sigmaFactor *= coarseSigmaFactor;
    }
    if (level >= minLevel + membraneSaturationLevels) p.membraneSaturation = 0;
    return p;
}

template <int D>
bool
MultiscaleResult<D>::isComplete() const
{
    return !isInterrupted() && lattice && !reports.empty();
}

template <int D> MultiscaleDriver<D>::MultiscaleDriver(const MultiscaleOptions& opts) : mOpts(opts)
{
    mOpts.validate();
}

template <int D>
MultiscaleResult<D>
MultiscaleDriver<D>::run(const LevelBuilder<D>& levels, const solver::IterationObserver& observer,
                         bool threaded, openvdb::util::NullInterrupter* interrupter) const
{
    return run([&levels](const LevelContext<D>& context) { return levels(context.level); },
               observer, LevelObserver(), threaded, interrupter);
}

template <int D>
MultiscaleResult<D>
MultiscaleDriver<D>::run(const ContextLevelBuilder<D>& levels,
                         const solver::IterationObserver& observer,
                         const LevelObserver& levelObserver, bool threaded,
                         openvdb::util::NullInterrupter* interrupter,
                         const InitialGuess<D>& initial) const
{
    MultiscaleResult<D> result;
    if (interrupter) interrupter->start("vdbmatch: multiscale descent");
    for (int l = mOpts.minLevel; l <= mOpts.maxLevel; ++l) {
        if (interrupter && interrupter->wasInterrupted()) {
            // Stopped before the level started: an empty report at this level.
            solver::Report stopped;
            stopped.level = l;
            stopped.status = solver::Status::Interrupted;
            result.reports.push_back(stopped);
            break;
        }
        LevelContext<D> context;
        context.level = l;
        context.previousLattice = result.lattice.get();
        context.previousDisplacement = result.lattice ? &result.displacement : nullptr;
        const Level<D> in = levels(context);
        if (!in.lattice || !in.shape1 || !in.shape2)
            OPENVDB_THROW(openvdb::ValueError,
                          "MultiscaleDriver::run: level " << l << " lacks a lattice or a shape");
        if (in.lattice->level() != l)
            OPENVDB_THROW(openvdb::ValueError, "MultiscaleDriver::run: the lattice of level "
                                                   << l << " has level " << in.lattice->level());
        if (!(in.bendingFactor >= 0 && in.bendingFactor <= 1))
            OPENVDB_THROW(openvdb::ValueError, "MultiscaleDriver::run: the bending factor of level "
                                                   << l << " is " << in.bendingFactor
                                                   << ", not in [0, 1]");

        NodeVectors<D> u = result.lattice ? prolongate<D>(*result.lattice, result.displacement,
                                                          *in.lattice, threaded)
                           : initial      ? initial(*in.lattice)
                                          : NodeVectors<D>::Zero(D, in.lattice->nodeCount());
        // Hanging nodes of the new lattice: their constraint values (equal to the prolongated
        // ones up to rounding when the lattice nests in the previous one).
        in.lattice->expand(u);

        EnergyParameters levelEnergy = mOpts.energyAt(l);
        levelEnergy.cBend *= in.bendingFactor;
        Energy<D> energy(*in.lattice, *in.shape1, *in.shape2, levelEnergy, mOpts.kind);
        std::optional<energy::LandmarkTerm<D>> landmarks;
        if (in.landmarks && !in.landmarks->source.empty()) {
            landmarks.emplace(*in.lattice, *in.landmarks);
            energy.setLandmarks(&*landmarks);
        }
        std::optional<energy::InnerDistanceTerm<D>> innerDistance;
        if (in.innerDistance && !in.innerDistance->points.empty()) {
            innerDistance.emplace(*in.lattice, *in.innerDistance);
            energy.setInnerDistance(&*innerDistance);
        }
        const Real tau = mOpts.metricTauFactor * energy.sigma() * energy.sigma();
        const solver::H1Metric<D> metric(*in.lattice, tau, mOpts.metric, threaded);
        solver::DescentOptions levelDescent = mOpts.descent;
        const Real tighten = std::pow(mOpts.toleranceCoarsening, mOpts.maxLevel - l);
        levelDescent.settleTolerance /= tighten;
        levelDescent.energyTolerance /= tighten;
        levelDescent.maxIterations = levelIterationLimit(mOpts, l);
        levelDescent.surfaceTolerance =
            mOpts.surfaceTestAt(l) ? mOpts.surfaceTolerance * in.lattice->h() / tighten : 0.0;
        solver::Descent<D> descent(energy, metric, levelDescent);
        // phi at the surface points as a function of u on this level's lattice.
        solver::SurfaceProbe<D> probe;
        if (in.surfacePoints && !in.surfacePoints->empty()) {
            const PiecewiseLinearInterpolator<D> locator(*in.lattice);
            typename PiecewiseLinearInterpolator<D>::Location loc;
            for (const Vec<D>& x : *in.surfacePoints)
                if (locator.locate(x, loc)) probe.add(loc.nodes, loc.weights);
        }
        descent.setSurfaceProbe(&probe);
        const solver::Report report = descent.run(u, observer, threaded, interrupter);

        result.lattice = in.lattice;
        result.displacement = std::move(u);
        result.reports.push_back(report);
        if (levelObserver) levelObserver(report);
        if (report.status == solver::Status::Interrupted) break;
    }
    if (interrupter) interrupter->end();
    return result;
}

template struct MultiscaleResult<2>;
template struct MultiscaleResult<3>;
template class MultiscaleDriver<2>;
template class MultiscaleDriver<3>;

} // namespace multiscale
} // namespace vdbmatch
