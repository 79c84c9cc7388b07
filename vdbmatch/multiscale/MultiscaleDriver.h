/// @file MultiscaleDriver.h
/// @brief The multiscale descent of paper sec:numerics: for l = lmin..lmax, descend on level l
///        from the prolongated result of level l-1 (the identity at lmin).
///
/// The caller provides, per level, the lattice and the two shape samplers (a LevelBuilder
/// callback); at level l the driver builds the Energy (sigma = sigmaFactor h_l = 2 h_l and the
/// volume weight c_vol sigma^theta, see Energy), the H1Metric with tau = tauFactor sigma^2, and
/// runs the Descent. The displacement of the previous level is prolongated exactly
/// (Prolongation.h), so det D phi > 0 carries over, then SimplexLattice::expand sets the hanging
/// nodes of the new lattice to their constraint values. For adaptive lattices, build level l
/// with buildAdaptiveLattice(..., coarser = lattice of level l-1) so that it nests in the
/// previous one: the prolongated field then already satisfies the constraints (up to rounding).
///
/// A level that ends with MaxIterations or LineSearchFailed is not an error: the next level
/// starts from its result (a finer level can usually continue). An interrupted level stops the
/// run; the result then holds the displacement of that level.
/// @see paper sec:numerics, tab:parameters
#pragma once

#include <vdbmatch/Parameters.h>
#include <vdbmatch/energy/InnerDistanceTerm.h>
#include <vdbmatch/energy/LandmarkTerm.h>
#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/lattice/SimplexLattice.h>
#include <vdbmatch/solver/Descent.h>
#include <vdbmatch/solver/H1Metric.h>

#include <openvdb/util/NullInterrupter.h>

#include <functional>
#include <memory>
#include <vector>

namespace vdbmatch {
namespace multiscale {

/// The inputs of one level. The shapes are sampled at x and phi(x) for x in the lattice's
/// cells: their coverage must include the closed unit box.
template <int D> struct Level
{
    std::shared_ptr<const SimplexLattice<D>> lattice;
    std::shared_ptr<const FieldSampler<D>> shape1; ///< fields of M1 (source)
    std::shared_ptr<const FieldSampler<D>> shape2; ///< fields of M2 (target)
    /// Points of M1 (Omega units) watched by the surface test (MultiscaleOptions::
    /// surfaceTolerance); null or empty: the test is off at this level. Must outlive run().
    const std::vector<Vec<D>>* surfacePoints = nullptr;
    /// Landmark pairs (Omega units) added to the energy (energy::LandmarkTerm); null or empty:
    /// none. Must outlive run().
    const LandmarkPairs<D>* landmarks = nullptr;
    /// Points of M1 and the field of M2 of the inner-distance term (energy::InnerDistanceTerm);
    /// null or empty: none. Must outlive run().
    const InnerDistanceSamples<D>* innerDistance = nullptr;
    /// Factor of energy.cBend at this level, in [0, 1] (1: the paper's eq:EsymBend weight).
    /// match() lowers it where a shape's Hessian is smoothed for noise
    /// (MatchOptions::noiseBendingPasses).
    Real bendingFactor = 1;
};

/// Builds the inputs of level l (called once per level, in increasing order, on the calling
/// thread). Signature: Level<D>(int level).
template <int D> using LevelBuilder = std::function<Level<D>(int)>;

/// What a level builder may use to shape level l: the result of level l-1 (null at the first
/// level), e.g. to refine the lattice near phi^{-1}(M2).
template <int D> struct LevelContext
{
    int level = 0;
    const SimplexLattice<D>* previousLattice = nullptr;
    const NodeVectors<D>* previousDisplacement = nullptr; ///< on previousLattice, Omega units
};

/// Builds the inputs of a level from its context (called once per level, in increasing order,
/// on the calling thread). Signature: Level<D>(const LevelContext<D>& context).
template <int D> using ContextLevelBuilder = std::function<Level<D>(const LevelContext<D>&)>;

/// The displacement the first level starts from instead of 0 (phi = Id), on that level's
/// lattice (D x nodeCount, Omega units), e.g. an earlier result (match --init). Called once, on
/// the calling thread; may throw. Signature: NodeVectors<D>(const SimplexLattice<D>& lattice).
template <int D> using InitialGuess = std::function<NodeVectors<D>(const SimplexLattice<D>&)>;

/// Called when a level ends (on the calling thread), with its report.
/// Signature: void(const solver::Report& report).
using LevelObserver = std::function<void(const solver::Report&)>;

/// Most iterations MultiscaleOptions::iterationCoarsening gives one level.
constexpr int MAX_LEVEL_ITERATIONS = 1000000;

struct MultiscaleOptions
{
    int minLevel = 4; ///< lmin (tab:parameters: 4)
    int maxLevel = 8; ///< lmax (tab:parameters: 8 in 3D, 9 in 2D)
    EnergyParameters energy = EnergyParameters::defaults(3);
    EnergyKind kind = EnergyKind::Symmetric;
    /// Metric weight tau = metricTauFactor * sigma^2 (H1Metric.h).
    Real metricTauFactor = solver::DEFAULT_METRIC_TAU_FACTOR;
    solver::H1MetricOptions metric;
    solver::DescentOptions descent;
    /// Cascadic schedule of the energy tests (DescentOptions::settleTolerance and
    /// energyTolerance): level l divides both by toleranceCoarsening^(maxLevel - l), so that coarse
    /// levels, where iterations are cheap, converge further than the finest one (>= 1; 1: the
    /// same everywhere).
    Real toleranceCoarsening = 1;
    /// Cascadic iteration limit: level l runs at most descent.maxIterations *
    /// iterationCoarsening^(maxLevel - l) iterations (rounded, at most MAX_LEVEL_ITERATIONS), so
    /// that a coarse level, whose iterations cost a fraction of the finest one's, is not stopped
    /// before it converges: what it leaves unconverged the finer levels pay for at their cost,
    /// or keep (>= 1; 1: the same limit everywhere, the paper).
    Real iterationCoarsening = 1;
    /// Surface test (DescentOptions::surfaceTolerance), in cells, at the last surfaceLevels
    /// levels: level l ends when phi on Level::surfacePoints moved by less than
    /// surfaceTolerance * h_l / toleranceCoarsening^(maxLevel - l) (path length of the mean
    /// motion over the last energyWindow iterations; 0: off). descent.surfaceTolerance is
    /// ignored: the driver sets it per level.
    Real surfaceTolerance = 0;
    /// Number of finest levels at which the surface test applies (>= 0). The coarse levels set
    /// the correspondence through slow tangential motion and must run to the energy test.
    int surfaceLevels = 1;
    /// The surface test also applies at every level >= surfaceFromLevel (0: none beyond the last
    /// surfaceLevels): from a fine enough level on, the cells resolve the shapes' parts and a
    /// level refines the fit rather than sets the correspondence (>= 0).
    int surfaceFromLevel = 0;
    /// Whether the surface test applies at level @a l (given a positive surfaceTolerance).
    bool surfaceTestAt(int l) const
    {
        return l > maxLevel - surfaceLevels || (surfaceFromLevel > 0 && l >= surfaceFromLevel);
    }
    /// Membrane weight below the finest level, an addition to the paper (which uses one c_mem):
    /// levels l < maxLevel use coarseMembraneFactor * energy.cMem in eq:EsymMem, the finest level
    /// energy.cMem (finite, in [0, MAX_COEFFICIENT]; 1: the paper). The coarse levels set the
    /// tangential correspondence (docs/performance.md); a stiffer membrane keeps it near
    /// isometric there, and the finest level, with the paper's weight, can still stretch.
    Real coarseMembraneFactor = 1;
    /// Volume weight below the finest level, an addition to the paper: levels l < maxLevel use
    /// coarseVolumeFactor * energy.cVol in eq:EsymVol, the finest level energy.cVol (finite, in
    /// [0, MAX_COEFFICIENT]; 1: the paper). A stiffer volume term resists the compression with
    /// which a coarse level can leave part of a limb behind; match()'s second path
    /// (MatchOptions::secondPath) uses it. The finest level's functional does not depend on it.
    Real coarseVolumeFactor = 1;
    /// Band width below the finest level, an addition to the paper (the sigma/h schedule):
    /// levels l < maxLevel use sigma = coarseSigmaFactor * energy.sigmaFactor * h_l, with the
    /// weights sigma^-q of eq:EsymMatch and sigma^theta of eq:EsymVol and the metric's
    /// tau sigma^2 that follow from it; the finest level the paper's sigma = 2h (in
    /// [MIN_COARSE_SIGMA_FACTOR, MAX_COARSE_SIGMA_FACTOR]; 1: the paper). Measured on the
    /// accuracy benchmark and not a default (docs/numerics.md "Band width below the finest
    /// level"). The largest factor keeps sigma = 6h within the exact 8-voxel band of the
    /// distances (DistanceField.h).
    Real coarseSigmaFactor = 1;
    static constexpr Real MIN_COARSE_SIGMA_FACTOR = 0.5;
    static constexpr Real MAX_COARSE_SIGMA_FACTOR = 3;
    /// Levels, from minLevel, at which energy.membraneSaturation acts (>= 0): levels
    /// l < minLevel + membraneSaturationLevels saturate the membrane densities, the finer ones
    /// use the paper's W. An addition to the paper (math/Saturation.h): the coarse levels choose
    /// the tangential correspondence, and the finer ones, with the paper's convex density, fit
    /// it.
    int membraneSaturationLevels = 2;

    /// The energy coefficients at level l: `energy`, with c_mem, c_vol and sigma/h scaled by
    /// coarseMembraneFactor, coarseVolumeFactor and coarseSigmaFactor below the finest level,
    /// and the membrane saturation only at the first membraneSaturationLevels levels.
    EnergyParameters energyAt(int level) const;

    /// tab:parameters for dimension 2 (Jump: levels 4..9) or 3 (Dolphin, Starfish: 4..8).
    static MultiscaleOptions defaults(int dim);
    /// Throws openvdb::ValueError naming the first invalid field.
    void validate() const;
};

/// The iteration limit of level @a l: opts.descent.maxIterations *
/// opts.iterationCoarsening^(opts.maxLevel - l), rounded, at most MAX_LEVEL_ITERATIONS (and not
/// below opts.descent.maxIterations).
int levelIterationLimit(const MultiscaleOptions& opts, int l);

template <int D> struct MultiscaleResult
{
    /// Lattice of the last level run and the displacement on it (D x nodeCount, Omega units).
    std::shared_ptr<const SimplexLattice<D>> lattice;
    NodeVectors<D> displacement;
    /// One report per level run, coarsest first.
    std::vector<solver::Report> reports;

    /// True if every level ran and none was interrupted.
    bool isComplete() const;
    bool isInterrupted() const
    {
        return !reports.empty() && reports.back().status == solver::Status::Interrupted;
    }
};

template <int D> class MultiscaleDriver
{
public:
    /// @throw openvdb::ValueError if the options are invalid
    explicit MultiscaleDriver(const MultiscaleOptions& opts);

    const MultiscaleOptions& options() const { return mOpts; }

    /// Runs levels minLevel..maxLevel.
    /// @param levels       inputs per level; lattice(l).level() must be l
    /// @param observer     per-iteration progress (IterationInfo::level tells the level)
    /// @param threaded     forwarded to the energy, metric, descent and prolongation
    /// @param interrupter  checked between levels and forwarded to the descent
    /// @throw openvdb::ValueError if a level's inputs are missing or inconsistent, and from
    ///        Energy / Descent (e.g. fields that do not cover the unit box).
    MultiscaleResult<D> run(const LevelBuilder<D>& levels,
                            const solver::IterationObserver& observer = {}, bool threaded = true,
                            openvdb::util::NullInterrupter* interrupter = nullptr) const;

    /// As above, with a builder that sees the previous level's result, a callback at the
    /// end of each level, and optionally the displacement of the first level (else 0).
    MultiscaleResult<D> run(const ContextLevelBuilder<D>& levels,
                            const solver::IterationObserver& observer,
                            const LevelObserver& levelObserver, bool threaded = true,
                            openvdb::util::NullInterrupter* interrupter = nullptr,
                            const InitialGuess<D>& initial = {}) const;

private:
    MultiscaleOptions mOpts;
};

extern template class MultiscaleDriver<2>;
extern template class MultiscaleDriver<3>;

} // namespace multiscale
} // namespace vdbmatch
