/// @file Match.cc
#include "Match.h"

#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/ExtremityMatching.h>
#include <vdbmatch/geometry/InnerDistance.h>
#include <vdbmatch/geometry/TriangleDistance.h>
#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <Eigen/Eigenvalues>
#include <openvdb/Exceptions.h>
#include <openvdb/tools/Interpolation.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

namespace vdbmatch {

namespace {

using Clock = std::chrono::steady_clock;

double
secondsSince(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

template <int D>
Vec<D>
toUnit(const UnitBoxPlacement& placement, const Vec<D>& world)
{
    openvdb::Vec3d w(0.0);
    for (int a = 0; a < D; ++a)
        w[a] = world[a];
    const openvdb::Vec3d u = placement.toUnit(w);
    Vec<D> out;
    for (int a = 0; a < D; ++a)
        out[a] = u[a];
    return out;
}

/// A world point as the report and the options hold them (2D: z ignored), in Omega units.
template <int D>
Vec<D>
toUnit(const UnitBoxPlacement& placement, const openvdb::Vec3d& world)
{
    const openvdb::Vec3d u = placement.toUnit(world);
    Vec<D> out;
    for (int a = 0; a < D; ++a)
        out[a] = u[a];
    return out;
}

template <int D>
Vec<D>
toWorld(const UnitBoxPlacement& placement, const Vec<D>& unit)
{
    openvdb::Vec3d u(0.5);
    for (int a = 0; a < D; ++a)
        u[a] = unit[a];
    const openvdb::Vec3d w = placement.toWorld(u);
    Vec<D> out;
    for (int a = 0; a < D; ++a)
        out[a] = w[a];
    return out;
}

template <int D>
Surface<D>
placed(const Surface<D>& world, const UnitBoxPlacement& placement, const char* what)
{
    Surface<D> unit = world;
    for (Vec<D>& p : unit.points) {
        p = toUnit<D>(placement, p);
        for (int a = 0; a < D; ++a) {
            if (!(p[a] > 0 && p[a] < 1)) {
                OPENVDB_THROW(openvdb::ValueError,
                              "match: the " << what
                                            << " does not fit in the unit box with this placement "
                                               "(a vertex maps outside (0,1)^d)");
            }
        }
    }
    return unit;
}

/// @a x as an openvdb point (2D: z = 1/2, the plane of Omega's placement).
template <int D>
openvdb::Vec3d
toPoint3(const Vec<D>& x)
{
    openvdb::Vec3d p(0.5);
    for (int a = 0; a < D; ++a)
        p[a] = x[a];
    return p;
}

/// Extra distance to allow for the error of a coarse tier of a sampler at x.
template <int D>
Real
tierSlack(const FieldSampler<D>& sampler, const Vec<D>& x)
{
    const int tier = sampler.findTier(x);
    return tier <= 0 ? Real(0) : sampler.voxelSize(std::size_t(tier));
}

} // namespace

MatchOptions
MatchOptions::paper(int dim)
{
    MatchOptions opts;
    opts.multiscale = multiscale::MultiscaleOptions::defaults(dim);
    opts.multiscale.descent.energyTolerance = DEFAULT_MATCH_ENERGY_TOLERANCE;
    opts.multiscale.descent.settleTolerance = DEFAULT_MATCH_SETTLE_TOLERANCE;
    opts.multiscale.toleranceCoarsening = DEFAULT_MATCH_TOLERANCE_COARSENING;
    opts.multiscale.surfaceTolerance = 0;
    opts.multiscale.surfaceLevels = DEFAULT_MATCH_SURFACE_LEVELS;
    opts.multiscale.surfaceFromLevel = DEFAULT_MATCH_SURFACE_FROM_LEVEL;
    opts.multiscale.metric.cgTolerance = DEFAULT_MATCH_METRIC_TOLERANCE;
    opts.multiscale.descent.gradientTolerance = DEFAULT_MATCH_GRADIENT_FLOOR;
    opts.anchorWeight = dim == 2 ? DEFAULT_ANCHOR_WEIGHT_2D : DEFAULT_ANCHOR_WEIGHT_3D;
    opts.anchorOptions.count = dim == 2 ? DEFAULT_ANCHOR_COUNT_2D : DEFAULT_ANCHOR_COUNT_3D;
    // Rigid segments (with the rigid limbs, off here) in 2D only: the 3D whole-body bend held
    // one and lost 26% (docs/numerics.md "Rigid segments").
    if (dim == 3) opts.rigidLimbOptions.segmentTo = 0;
    return opts;
}

MatchOptions
MatchOptions::defaults(int dim)
{
    MatchOptions opts = paper(dim);
    opts.multiscale.surfaceTolerance =
        dim == 2 ? DEFAULT_MATCH_SURFACE_TOLERANCE_2D : DEFAULT_MATCH_SURFACE_TOLERANCE_3D;
    opts.multiscale.coarseMembraneFactor = DEFAULT_MATCH_COARSE_MEMBRANE_FACTOR;
    opts.multiscale.energy.membraneSaturation =
        dim == 2 ? DEFAULT_MATCH_MEMBRANE_SATURATION_2D : DEFAULT_MATCH_MEMBRANE_SATURATION_3D;
    opts.multiscale.membraneSaturationLevels = DEFAULT_MATCH_MEMBRANE_SATURATION_LEVELS;
    if (dim == 2) opts.multiscale.metricTauFactor = DEFAULT_MATCH_METRIC_TAU_2D;
    opts.autoLandmarks = true;
    opts.autoAnchors = true;
    opts.landmarkAnchors = true;
    opts.innerDistanceWeight =
        dim == 2 ? DEFAULT_INNER_DISTANCE_WEIGHT_2D : DEFAULT_INNER_DISTANCE_WEIGHT_3D;
    opts.secondPath = true;
    opts.hessianNoiseFactor = NOISE_SMOOTHING_LENGTH_FACTOR;
    opts.hessianLatticeNoiseFactor = dim == 3 ? LATTICE_NOISE_SMOOTHING_FACTOR_3D : 0.0;
    opts.noiseBendingPasses = DEFAULT_NOISE_BENDING_PASSES;
    opts.anchorNoiseFactor = dim == 3 ? DEFAULT_ANCHOR_NOISE_FACTOR_3D : 0.0;
    opts.rigidLimbWeight = DEFAULT_RIGID_LIMB_WEIGHT;
    opts.rigidLimbAnchorRadius = dim == 3 ? DEFAULT_RIGID_LIMB_ANCHOR_RADIUS_3D : 0.0;
    return opts;
}

void
MatchOptions::validate() const
{
    multiscale.validate();
    if (!(margin >= 0 && margin < 0.5)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: margin must be in [0, 0.5), got " << margin);
    }
    if (!(refinementMarginCells >= 0 && refinementMarginCells <= MAX_REFINEMENT_MARGIN_CELLS)) {
        OPENVDB_THROW(openvdb::ValueError, "MatchOptions: refinementMarginCells must be in [0, "
                                               << MAX_REFINEMENT_MARGIN_CELLS << "], got "
                                               << refinementMarginCells);
    }
    if (sourceLandmarks.size() != targetLandmarks.size()) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: " << sourceLandmarks.size() << " source landmarks but "
                                       << targetLandmarks.size() << " target landmarks");
    }
    if (!(landmarkWeight >= 0) || !std::isfinite(landmarkWeight)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: landmarkWeight must be finite and >= 0, got "
                          << landmarkWeight);
    }
    if (!(autoLandmarkMinMotion >= 0) || !std::isfinite(autoLandmarkMinMotion)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: autoLandmarkMinMotion must be finite and >= 0, got "
                          << autoLandmarkMinMotion);
    }
    if (!(rigidLimbWeight >= 0) || !std::isfinite(rigidLimbWeight)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: rigidLimbWeight must be finite and >= 0, got "
                          << rigidLimbWeight);
    }
    if (!(rigidLimbMinMotion >= 0) || !std::isfinite(rigidLimbMinMotion)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: rigidLimbMinMotion must be finite and >= 0, got "
                          << rigidLimbMinMotion);
    }
    if (!(rigidLimbAnchorRadius >= 0) || !std::isfinite(rigidLimbAnchorRadius)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: rigidLimbAnchorRadius must be finite and >= 0, got "
                          << rigidLimbAnchorRadius);
    }
    if (!(rigidLimbOptions.count >= 2)) {
        OPENVDB_THROW(openvdb::ValueError, "MatchOptions: the rigid limbs' count must be >= 2, got "
                                               << rigidLimbOptions.count);
    }
    if (!(anchorWeight >= 0) || !std::isfinite(anchorWeight)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: anchorWeight must be finite and >= 0, got " << anchorWeight);
    }
    if (!(anchorOptions.tolerance >= 0) || !std::isfinite(anchorOptions.tolerance) ||
        !(anchorOptions.radius >= 0) || !std::isfinite(anchorOptions.radius)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: the anchor tolerance and radius must be finite and >= 0, got "
                          << anchorOptions.tolerance << " and " << anchorOptions.radius);
    }
    if (!(anchorNoiseFactor >= 0) || !std::isfinite(anchorNoiseFactor)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: anchorNoiseFactor must be finite and >= 0, got "
                          << anchorNoiseFactor);
    }
    if (!(hessianNoiseFactor >= 0) || !std::isfinite(hessianNoiseFactor)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: hessianNoiseFactor must be finite and >= 0, got "
                          << hessianNoiseFactor);
    }
    if (!(hessianLatticeNoiseFactor >= 0) || !std::isfinite(hessianLatticeNoiseFactor)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: hessianLatticeNoiseFactor must be finite and >= 0, got "
                          << hessianLatticeNoiseFactor);
    }
    if (!(noiseBendingPasses >= 0) || !std::isfinite(noiseBendingPasses)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: noiseBendingPasses must be finite and >= 0, got "
                          << noiseBendingPasses);
    }
    if (!(secondPathShare >= 0 && secondPathShare <= 1)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: secondPathShare must be in [0, 1], got " << secondPathShare);
    }
    if (secondPathTarget && !secondPath) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: secondPathTarget needs secondPath (--second-path-target on "
                      "needs --second-path on; --preset paper turns it off)");
    }
    if (!(innerDistanceWeight >= 0) || !std::isfinite(innerDistanceWeight) ||
        !(innerDistanceTolerance >= 0) || !std::isfinite(innerDistanceTolerance)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: the inner-distance weight and tolerance must be finite and "
                      ">= 0, got "
                          << innerDistanceWeight << " and " << innerDistanceTolerance);
    }
    if (!(innerDistanceRatio >= 1) || !std::isfinite(innerDistanceRatio)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: innerDistanceRatio must be finite and >= 1, got "
                          << innerDistanceRatio);
    }
    if (innerDistanceLevel > MAX_INNER_DISTANCE_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError, "MatchOptions: innerDistanceLevel must be at most "
                                               << MAX_INNER_DISTANCE_LEVEL << ", got "
                                               << innerDistanceLevel);
    }
    if (autoLandmarkLevels < 1) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: autoLandmarkLevels must be >= 1, got " << autoLandmarkLevels);
    }
    if (coarsestLevel > multiscale.minLevel) {
        OPENVDB_THROW(openvdb::ValueError, "MatchOptions: coarsestLevel ("
                                               << coarsestLevel << ") must not exceed minLevel ("
                                               << multiscale.minLevel << ")");
    }
}

void
MatchOptions::validate(int dim) const
{
    validate();
    if (multiscale.maxLevel > maxMatchLevel(dim)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: the finest level is at most "
                          << maxMatchLevel(dim) << " in " << dim << "D (got " << multiscale.maxLevel
                          << "; memory grows " << (dim == 2 ? 2 : 4)
                          << "x per level: level 8 of a 3D pair takes about 0.8 GB)");
    }
    if (dim == 3 && innerDistanceLevel > MAX_INNER_DISTANCE_LEVEL_3D) {
        OPENVDB_THROW(openvdb::ValueError,
                      "MatchOptions: innerDistanceLevel is at most "
                          << MAX_INNER_DISTANCE_LEVEL_3D << " in 3D (got " << innerDistanceLevel
                          << "; each extremity's field takes 22 bytes per node while it is "
                             "computed, (2^level + 1)^3 nodes: 370 MB at level 8)");
    }
}

template <int D>
bool
MatchResult<D>::isComplete() const
{
    return lattice && !isInterrupted() && !levels.empty();
}

template <int D>
LatticeSummary
summarize(const SimplexLattice<D>& lattice)
{
    const LatticeStats stats = lattice.stats();
    LatticeSummary s;
    s.cells = lattice.cellCount();
    s.simplices = lattice.simplexCount();
    s.nodes = stats.nodes;
    s.unknowns = stats.freeNodes;
    s.hangingNodes = stats.hangingNodes;
    s.denseNodes = stats.denseNodes;
    s.cellsPerLog2Size = stats.cellsPerLog2Size;
    return s;
}

namespace {

/// Reduces value(D phi) over every simplex of the lattice (D phi of Id + u, exact per simplex):
/// parallel over cells, combined with @a combine from @a init.
template <int D, typename Value, typename Combine>
Real
reduceSimplexJacobians(const SimplexLattice<D>& lattice, const NodeVectors<D>& u, Real init,
                       const Value& value, const Combine& combine)
{
    const auto& cells = lattice.cells();
    const auto& paths = KuhnSplit<D>::path();
    const auto& axes = KuhnSplit<D>::axis();
    return tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, cells.size()), init,
        [&](const tbb::blocked_range<std::size_t>& r, Real best) {
            for (std::size_t ci = r.begin(); ci != r.end(); ++ci) {
                const auto& cell = cells[ci];
                const Real side = lattice.h() * Real(1 << cell.log2Size);
                for (std::size_t p = 0; p < paths.size(); ++p) {
                    Mat<D> A = Mat<D>::Identity();
                    for (int m = 1; m <= D; ++m) {
                        const int a = axes[p][m];
                        const auto from = cell.corners[paths[p][m - 1]];
                        const auto to = cell.corners[paths[p][m]];
                        A.col(a) += (u.col(to) - u.col(from)) / side;
                    }
                    best = combine(best, value(A));
                }
            }
            return best;
        },
        combine);
}

} // namespace

template <int D>
Real
lipschitzBound(const SimplexLattice<D>& lattice, const NodeVectors<D>& u)
{
    // Largest singular value: sqrt of the largest eigenvalue of A^T A.
    return reduceSimplexJacobians<D>(
        lattice, u, Real(1),
        [](const Mat<D>& A) {
            Eigen::SelfAdjointEigenSolver<Mat<D>> eig;
            eig.computeDirect(A.transpose() * A, Eigen::EigenvaluesOnly);
            return std::sqrt(std::max(Real(0), eig.eigenvalues()[D - 1]));
        },
        [](Real a, Real b) { return std::max(a, b); });
}

template <int D>
Real
minDeterminant(const SimplexLattice<D>& lattice, const NodeVectors<D>& u)
{
    return reduceSimplexJacobians<D>(
        lattice, u, INF, [](const Mat<D>& A) { return A.determinant(); },
        [](Real a, Real b) { return std::min(a, b); });
}

namespace {

/// The two shapes' noise as the anchors' tolerance follows it (Omega units; 0: not read).
struct AnchorNoise
{
    double correlated = 0; ///< hypot of the shapes' correlatedNoise()
    double lattice = 0;    ///< hypot of the shapes' lattice readings, white noise included
};

/// MatchOptions::autoLandmarks: the paired extremities of the two shapes (Omega units in,
/// world units out), and the anchors, sought with a tolerance of at least
/// MatchOptions::anchorNoiseFactor times @a noise.correlated; where a rigid limb is held and
/// the anchors are sought again nearer its joint, times @a noise.lattice.
/// With @a anchorsOnly (MatchOptions::landmarkAnchors: the caller's landmarks act instead) the
/// paired extremities are not landmarks (used stays false): they decide whether the motion is
/// an articulation, and so whether the anchors act, and they are the inner-distance term's.
template <int D>
AutoLandmarkSummary
autoLandmarks(const Surface<D>& unitSource, const Surface<D>& unitTarget,
              const UnitBoxPlacement& placement, const MatchOptions& opts, const AnchorNoise& noise,
              bool anchorsOnly)
{
    const Clock::time_point start = Clock::now();
    AutoLandmarkSummary out;
    out.requested = true;
    ExtremityOptions eo;
    eo.threaded = opts.threaded;
    Extremities<D> a, b;
    auto findA = [&] { a = findExtremities<D>(unitSource, eo); };
    auto findB = [&] { b = findExtremities<D>(unitTarget, eo); };
    detail::invokeBoth(opts.threaded, findA, findB);
    out.sourceExtremities = a.size();
    out.targetExtremities = b.size();
    const ExtremityPairing pairing = matchExtremities<D>(a, b);
    out.seconds = secondsSince(start);
    if (!pairing.ok) {
        if (anchorsOnly) {
            out.reason = "the given landmarks act instead";
            out.anchorReason = "the extremities cannot be paired: " + pairing.reason;
        } else {
            out.reason = pairing.reason;
        }
        return out;
    }
    out.paired = true;
    out.distortion = pairing.distortion;
    out.candidates = pairing.candidates;
    double leastMotion = std::numeric_limits<double>::infinity(); // for the anchors, below
    for (const auto& [i, j] : pairing.pairs) {
        const double motion = (a.points[i] - b.points[j]).norm();
        out.maxMotion = std::max(out.maxMotion, motion);
        leastMotion = std::min(leastMotion, motion);
    }
    const int first = opts.multiscale.minLevel;
    out.minMotion = opts.autoLandmarkMinMotion * opts.multiscale.energyAt(first).sigmaFactor *
                    std::ldexp(1.0, -first);
    if (anchorsOnly) {
        out.reason = "the given landmarks act instead; the paired extremities only decide the "
                     "anchors and the inner distance";
    } else if (!(out.maxMotion > out.minMotion)) {
        std::ostringstream s;
        s << "every extremity moves by less than " << opts.autoLandmarkMinMotion
          << " sigma of the first level (at most " << out.maxMotion << " against " << out.minMotion
          << ", unit box): the shape energy alone decides";
        out.reason = s.str();
        return out;
    }
    const auto world = [&](const Vec<D>& p) {
        return placement.toWorld(openvdb::Vec3d(p[0], p[1], D == 3 ? p[D - 1] : 0.5));
    };
    if (!anchorsOnly) {
        out.used = true;
        out.lastLevel = opts.multiscale.minLevel + opts.autoLandmarkLevels - 1;
    }
    for (const auto& [i, j] : pairing.pairs) {
        openvdb::Vec3d wa = world(a.points[i]), wb = world(b.points[j]);
        if (D == 2) wa[2] = wb[2] = 0;
        out.source.push_back(wa);
        out.target.push_back(wb);
    }
    // Anchors only when some extremity stays while another moves (ANCHOR_STILL_RATIO): the
    // motion is then articulated, and what coincides in both shapes kept its place. When every
    // extremity moves (a turn of the whole shape), or all move alike (a twist of the body), a
    // coinciding part may have slid along itself, and holding it would be wrong.
    if (opts.autoAnchors && !(leastMotion <= opts.anchorOptions.radius)) {
        std::ostringstream s;
        s << "every extremity moves (the least by " << leastMotion << " > the anchor radius "
          << opts.anchorOptions.radius << ", unit box)";
        out.anchorReason = s.str();
    } else if (opts.autoAnchors && !(leastMotion <= ANCHOR_STILL_RATIO * out.maxMotion)) {
        std::ostringstream s;
        s << "the extremities move alike (the least by " << leastMotion << ", the most by "
          << out.maxMotion << ", unit box: a twist or a turn, not an articulation)";
        out.anchorReason = s.str();
    } else if (opts.autoAnchors) {
        StillAnchorOptions ao = opts.anchorOptions;
        ao.threaded = opts.threaded;
        ao.tolerance = std::max(ao.tolerance, opts.anchorNoiseFactor * noise.correlated);
        const StillAnchors<D> anchors = findStillAnchors<D>(unitSource, unitTarget, ao);
        out.anchorTolerance = ao.tolerance;
        out.anchorRadius = ao.radius;
        out.anchorCoincidentShare = anchors.coincidentShare();
        if (anchors.points.empty()) {
            std::ostringstream s;
            s << "the shapes coincide nowhere (within " << ao.tolerance << ", unit box)";
            out.anchorReason = s.str();
        }
        const auto setAnchors = [&](const std::vector<Vec<D>>& points) {
            out.anchors.clear();
            for (const Vec<D>& p : points) {
                openvdb::Vec3d w = world(p);
                if (D == 2) w[2] = 0;
                out.anchors.push_back(w);
            }
        };
        setAnchors(anchors.points);
        // Rigid limbs: the moving extremities' limbs, from the anchors' joint.
        if (opts.rigidLimbWeight > 0 && !anchors.points.empty()) {
            std::vector<Vec<D>> tipsA, tipsB;
            double largest = 0;
            for (const auto& [i, j] : pairing.pairs) {
                tipsA.push_back(a.points[i]);
                tipsB.push_back(b.points[j]);
                largest = std::max(largest, (a.points[i] - b.points[j]).norm());
            }
            RigidLimbOptions lo = opts.rigidLimbOptions;
            lo.threaded = opts.threaded;
            // When some extremity moved beyond K sigma of the first level, every extremity that
            // moves (farther than RIGID_LIMB_MOTION_RATIO of the largest motion) is a limb too,
            // so that two limbs swung alike are held alike though one of them moved a little
            // less than K sigma.
            lo.minMotion = opts.rigidLimbMinMotion * opts.multiscale.energyAt(first).sigmaFactor *
                           std::ldexp(1.0, -first);
            if (largest > lo.minMotion) {
                lo.minMotion = std::min(lo.minMotion, RIGID_LIMB_MOTION_RATIO * largest);
            }
            out.limbMinMotion = lo.minMotion;
            const RigidLimbs<D> limbs =
                findRigidLimbs<D>(unitSource, unitTarget, tipsA, tipsB, anchors.points, lo);
            for (const RigidLimb<D>& l : limbs.limbs)
                out.limbs.push_back(l); // the fit, without the map
            for (std::size_t k = 0; k < limbs.source.size(); ++k) {
                openvdb::Vec3d wa = world(limbs.source[k]), wb = world(limbs.target[k]);
                if (D == 2) wa[2] = wb[2] = 0;
                out.limbSource.push_back(wa);
                out.limbTarget.push_back(wb);
            }
            // A limb swung beyond the first band drags the skin next to its joint: the anchors
            // come nearer the joints (a smaller patch), sought again, with a tolerance that
            // follows all of the shapes' noise, white noise too (which leaves most of a scan's
            // skin next to the joint off the source by more than the fixed tolerance).
            const double r = opts.rigidLimbAnchorRadius;
            if (!limbs.source.empty() && r > 0 && r < ao.radius) {
                StillAnchorOptions near = ao;
                near.radius = r;
                near.tolerance = std::max(ao.tolerance, opts.anchorNoiseFactor * noise.lattice);
                const StillAnchors<D> closer = findStillAnchors<D>(unitSource, unitTarget, near);
                if (!closer.points.empty()) {
                    out.anchorRadius = r;
                    out.anchorTolerance = near.tolerance;
                    out.anchorCoincidentShare = closer.coincidentShare();
                    setAnchors(closer.points);
                }
            }
        }
        out.seconds = secondsSince(start);
    }
    return out;
}

/// MatchOptions::innerDistanceWeight: F1_k, F2_k from each pair k of extremities (@a landmarks,
/// Omega units: @a pairs' paired extremities, landmarks or beside given ones) and the vertices of
/// M1 with their shares of its measure and nearest extremity; @a samples stays empty when the
/// term does not act (the summary says why).
template <int D>
InnerDistanceSummary
innerDistanceSamples(const Surface<D>& unitSource, const Surface<D>& unitTarget,
                     const LandmarkPairs<D>& landmarks, const AutoLandmarkSummary& pairs,
                     const MatchOptions& opts, InnerDistanceSamples<D>& samples)
{
    const Clock::time_point start = Clock::now();
    InnerDistanceSummary out;
    out.requested = true;
    out.weight = opts.innerDistanceWeight;
    out.tolerance = opts.innerDistanceTolerance;
    out.level = opts.innerDistanceLevel > 0
                    ? opts.innerDistanceLevel
                    : (D == 3 ? DEFAULT_INNER_DISTANCE_LEVEL_3D : DEFAULT_INNER_DISTANCE_LEVEL_2D);
    if (pairs.source.empty()) {
        out.reason = "the automatic landmarks do not act";
        return out;
    }
    // Only for an articulation, as the anchors: a stretch or a twist changes F itself.
    if (pairs.anchors.empty()) {
        out.reason = "the automatic anchors do not act" +
                     (pairs.anchorReason.empty() ? std::string() : ": " + pairs.anchorReason);
        return out;
    }
    std::vector<InnerDistanceField<D>> f1, f2;
    auto buildSource = [&] {
        f1 = innerDistanceFields<D>(unitSource, landmarks.source, out.level, opts.threaded);
    };
    auto buildTarget = [&] {
        f2 = innerDistanceFields<D>(unitTarget, landmarks.target, out.level, opts.threaded);
    };
    detail::invokeBoth(opts.threaded, buildSource, buildTarget);
    for (std::size_t k = 0; k < f1.size(); ++k) {
        if (f1[k].empty() || f2[k].empty()) {
            out.reason = "a shape has no lattice node inside at the level of F";
            out.seconds = secondsSince(start);
            return out;
        }
    }
    for (InnerDistanceField<D>& f : f2)
        samples.targets.push_back(std::make_shared<const InnerDistanceField<D>>(std::move(f)));
    // Each vertex carries 1/D of the measure of its elements.
    std::vector<Real> share(unitSource.points.size(), 0);
    Real total = 0;
    for (const auto& e : unitSource.elements) {
        Real m;
        if constexpr (D == 2) {
            m = (unitSource.points[std::size_t(e[1])] - unitSource.points[std::size_t(e[0])])
                    .norm();
        } else {
            const Vec<3> p = unitSource.points[std::size_t(e[0])];
            m = 0.5 * (unitSource.points[std::size_t(e[1])] - p)
                          .cross(unitSource.points[std::size_t(e[2])] - p)
                          .norm();
        }
        for (int k = 0; k < D; ++k)
            share[std::size_t(e[std::size_t(k)])] += m / D;
        total += m;
    }
    // Each vertex keeps its inner distance to the extremity of M1 nearest to it (the first of
    // equals), when the next one is at least innerDistanceRatio times as far: where two are
    // about as near, the paths from both cross a joint, which an articulation turns.
    Real kept = 0;
    for (std::size_t i = 0; i < unitSource.points.size(); ++i) {
        if (!(share[i] > 0)) continue;
        Real best;
        const int nearest = ownSource<D>(f1, unitSource.points[i], opts.innerDistanceRatio, best);
        if (nearest < 0) continue;
        kept += share[i];
        samples.points.push_back(unitSource.points[i]);
        samples.values.push_back(best);
        samples.fields.push_back(uint32_t(nearest));
        samples.weights.push_back(Real(opts.innerDistanceWeight) * share[i] / total);
    }
    samples.tolerance = Real(opts.innerDistanceTolerance);
    out.ratio = opts.innerDistanceRatio;
    out.points = samples.points.size();
    out.share = total > 0 ? double(kept / total) : 0.0;
    if (samples.points.empty()) {
        out.reason = "no vertex of M1 has an extremity clearly its own (innerDistanceRatio)";
        samples = InnerDistanceSamples<D>();
        out.seconds = secondsSince(start);
        return out;
    }
    out.used = true;
    // At phi = Id: how far F changes between the shapes at the same place (means over the
    // points in the term, as InnerDistanceTerm::residual()).
    Real sum = 0, beyond = 0, weights = 0;
    for (std::size_t i = 0; i < samples.points.size(); ++i) {
        Real f;
        samples.targets[samples.fields[i]]->sample(samples.points[i], f);
        const Real r = std::abs(f - samples.values[i]);
        const Real w = samples.weights[i];
        sum += w * r;
        weights += w;
        if (r > samples.tolerance) beyond += w;
    }
    out.startMean = sum / weights;
    out.startBeyond = beyond / weights;
    out.seconds = secondsSince(start);
    return out;
}

/// |d2(phi(v))| over the points v (Omega units), with @a target the finest level's sampler;
/// @a moved receives phi(v).
struct SurfaceResidual
{
    double sum = 0, max = 0;
    std::size_t samples = 0, far = 0;
    std::size_t capped = 0;    ///< samples counted at a band's half width (targetResidual)
    std::size_t maxVertex = 0; ///< the vertex of the largest (the first of equals)
    double farShare() const { return samples ? double(far) / double(samples) : 0.0; }
};

template <int D>
SurfaceResidual
surfaceResidual(const SimplexLattice<D>& lattice, const NodeVectors<D>& u,
                const std::vector<Vec<D>>& points, const FieldSampler<D>* target, Real far,
                std::vector<Vec<D>>& moved)
{
    const multiscale::PiecewiseLinearInterpolator<D> phi(lattice);
    SurfaceResidual out;
    moved.resize(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        Vec<D> du = Vec<D>::Zero();
        phi.evaluate(u, points[i], du);
        moved[i] = points[i] + du;
        Real d;
        if (target && target->sampleDistance(moved[i], d)) {
            out.sum += std::abs(d);
            if (std::abs(d) > out.max) {
                out.max = std::abs(d);
                out.maxVertex = i;
            }
            if (std::abs(d) > far) ++out.far;
            ++out.samples;
        }
    }
    return out;
}

/// Exact distance from @a y to the elements of @a s (all of them: for the few points beyond the
/// band of targetResidual).
template <int D>
double
elementDistance(const Surface<D>& s, const Vec<D>& y)
{
    double best = std::numeric_limits<double>::infinity();
    for (const auto& e : s.elements) {
        if constexpr (D == 3) {
            auto v = [&](int k) {
                const Vec<3>& q = s.points[std::size_t(e[std::size_t(k)])];
                return openvdb::Vec3d(q[0], q[1], q[2]);
            };
            best = std::min(best, detail::triangleDistanceSqr(openvdb::Vec3d(y[0], y[1], y[2]),
                                                              v(0), v(1), v(2)));
        } else {
            best = std::min(best, detail::segmentDistanceSqr(y, s.points[std::size_t(e[0])],
                                                             s.points[std::size_t(e[1])]));
        }
    }
    return std::sqrt(best);
}

/// dist(y, phi(M1)) over the points y of M2 (Omega units), MatchResult::targetResidual: the
/// unsigned distance of the moved source surface on a band of TARGET_RESIDUAL_BAND_CELLS cells at
/// @a level (distanceBand, exact at the nodes), interpolated at y. Points within a cell of the
/// band's edge or beyond get the exact distance to every element instead, unless that would
/// take more than TARGET_RESIDUAL_EXACT_BUDGET point-element distances: then they count at the
/// band's half width (SurfaceResidual::capped). Each point is independent and the sums run in
/// order, so the result does not depend on the thread count.
template <int D>
SurfaceResidual
targetResidual(const Surface<D>& unitSource, const std::vector<Vec<D>>& moved,
               const std::vector<Vec<D>>& targetPoints, int level, Real far, bool threaded)
{
    Surface<D> deformed;
    deformed.points = moved;
    deformed.elements = unitSource.elements;
    const openvdb::FloatGrid::Ptr band =
        distanceBand<D>(deformed, level, TARGET_RESIDUAL_BAND_CELLS, threaded);
    const double h = std::ldexp(1.0, -level), cap = TARGET_RESIDUAL_BAND_CELLS * h;
    const openvdb::FloatGrid::ConstAccessor acc = band->getConstAccessor();
    const openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler>
        sampler(acc, band->transform());
    std::vector<double> d(targetPoints.size());
    std::vector<std::size_t> beyond; // within a cell of the band's edge, or outside it
    for (std::size_t i = 0; i < targetPoints.size(); ++i) {
        openvdb::Vec3d p(0.0); // 2D: the band is the slice k = 0
        for (int a = 0; a < D; ++a)
            p[a] = targetPoints[i][a];
        d[i] = std::min(cap, std::abs(double(sampler.wsSample(p))));
        if (d[i] > cap - h) beyond.push_back(i);
    }
    SurfaceResidual out;
    if (double(beyond.size()) * double(deformed.elements.size()) <= TARGET_RESIDUAL_EXACT_BUDGET) {
        detail::forEachIndex(beyond.size(), threaded, [&](std::size_t k) {
            d[beyond[k]] = elementDistance<D>(deformed, targetPoints[beyond[k]]);
        });
    } else {
        out.capped = beyond.size();
    }
    for (std::size_t i = 0; i < d.size(); ++i) {
        out.sum += d[i];
        if (d[i] > out.max) {
            out.max = d[i];
            out.maxVertex = i;
        }
        if (d[i] > far) ++out.far;
        ++out.samples;
    }
    return out;
}

/// MatchResidual of a SurfaceResidual, world and Omega units.
MatchResidual
toMatchResidual(const SurfaceResidual& r, const UnitBoxPlacement& placement)
{
    MatchResidual m;
    m.samples = r.samples;
    m.meanUnit = r.samples ? r.sum / double(r.samples) : 0.0;
    m.maxUnit = r.max;
    m.farShare = r.farShare();
    m.capped = r.capped;
    m.maxVertex = r.maxVertex;
    m.meanWorld = placement.toWorldLength(m.meanUnit);
    m.maxWorld = placement.toWorldLength(m.maxUnit);
    return m;
}

} // namespace

template <int D>
MatchResult<D>
match(const Surface<D>& source, const Surface<D>& target, const UnitBoxPlacement& placement,
      const MatchOptions& optsIn, const MatchObserver& observer,
      openvdb::util::NullInterrupter* interrupter)
{
    const Clock::time_point start = Clock::now();
    optsIn.validate(D);
    checkSurface(source, "source");
    checkSurface(target, "target");
    MatchOptions opts = optsIn;
    // The shape operator's eigenvalue floor is an energy parameter (tab:parameters).
    opts.sampler.fields.tau = opts.multiscale.energy.tau;
    opts.sampler.threaded = opts.threaded;

    const Surface<D> unitSource = placed(source, placement, "source");
    const Surface<D> unitTarget = placed(target, placement, "target");
    const int coarsestLevel =
        opts.coarsestLevel > 0 ? opts.coarsestLevel : opts.multiscale.minLevel;
    // The membrane saturation acts at the first levels of the requested range, coarsestLevel on:
    // a run that resumes or refines an earlier result (minLevel above it) has fewer left.
    opts.multiscale.membraneSaturationLevels = std::max(
        0, coarsestLevel + opts.multiscale.membraneSaturationLevels - opts.multiscale.minLevel);

    MatchResult<D> result;
    result.placement = placement;
    // Each shape's Hessian smoothed over a length from its own noise (geometry/SurfaceNoise.h).
    ShapeSamplerOptions sourceSampler = opts.sampler, targetSampler = opts.sampler;
    // The length is the larger of the vertex and the lattice readings' (docs/numerics.md
    // "Correlated noise"): white vertex noise reads higher on the first, noise correlated over
    // a few vertices on the second.
    AnchorNoise anchorNoise; // Omega units
    if (opts.hessianNoiseFactor > 0) {
        NoiseReading noise[2];
        detail::invokeBoth(
            opts.threaded,
            [&] {
                noise[0] = readNoise(unitSource, opts.hessianNoiseFactor,
                                     opts.hessianLatticeNoiseFactor, opts.threaded);
            },
            [&] {
                noise[1] = readNoise(unitTarget, opts.hessianNoiseFactor,
                                     opts.hessianLatticeNoiseFactor, opts.threaded);
            });
        result.shapeNoise = {noise[0].vertex, noise[1].vertex};
        result.latticeNoise = {noise[0].lattice, noise[1].lattice};
        result.smoothingLength = {noise[0].length, noise[1].length};
        sourceSampler.fields.hessianSmoothingLength = noise[0].length;
        targetSampler.fields.hessianSmoothingLength = noise[1].length;
        // The anchors' tolerance follows the noise the two shapes add up to.
        anchorNoise.correlated = std::hypot(correlatedNoise(noise[0]), correlatedNoise(noise[1]));
        anchorNoise.lattice = std::hypot(noise[0].lattice, noise[1].lattice);
    }

    // The landmarks act at every level, automatic ones at the first autoLandmarkLevels only.
    int lastLandmarkLevel = std::numeric_limits<int>::max();
    if (opts.autoLandmarks && opts.sourceLandmarks.empty() && opts.initial) {
        // An earlier result already carries the correspondence, and its first level may be
        // fine, where landmarks as imprecise as these would only pull it off.
        result.autoLandmarks.requested = true;
        result.autoLandmarks.reason = "the run starts from an earlier result";
    } else if (opts.autoLandmarks && opts.sourceLandmarks.empty()) {
        result.autoLandmarks =
            autoLandmarks(unitSource, unitTarget, placement, opts, anchorNoise, false);
        lastLandmarkLevel = result.autoLandmarks.lastLevel;
        opts.sourceLandmarks = result.autoLandmarks.source;
        opts.targetLandmarks = result.autoLandmarks.target;
    } else if (opts.autoAnchors && opts.landmarkAnchors && !opts.sourceLandmarks.empty() &&
               !opts.initial) {
        // The given landmarks act at every level; the extremities only decide the anchors.
        result.autoLandmarks =
            autoLandmarks(unitSource, unitTarget, placement, opts, anchorNoise, true);
    }
    if (result.autoLandmarks.requested && observer.autoLandmarks)
        observer.autoLandmarks(result.autoLandmarks);
    // Landmarks in Omega units; the source points must lie inside Omega (the target points
    // need not: the term pulls phi(a_k) towards them).
    LandmarkPairs<D> landmarks;
    landmarks.weight = Real(opts.landmarkWeight);
    for (std::size_t k = 0; k < opts.sourceLandmarks.size(); ++k) {
        const Vec<D> a = toUnit<D>(placement, opts.sourceLandmarks[k]);
        const Vec<D> b = toUnit<D>(placement, opts.targetLandmarks[k]);
        if (!a.allFinite() || !b.allFinite()) {
            OPENVDB_THROW(openvdb::ValueError, "match: landmark pair "
                                                   << k + 1
                                                   << " has a coordinate that is not finite");
        }
        for (int i = 0; i < D; ++i) {
            if (!(a[i] > 0 && a[i] < 1)) {
                OPENVDB_THROW(openvdb::ValueError,
                              "match: source landmark "
                                  << k + 1
                                  << " lies outside the unit box of the shapes (it should lie on "
                                     "or near the source shape)");
            }
        }
        landmarks.source.push_back(a);
        landmarks.target.push_back(b);
        Vec<D> first = a; // phi(a_k) at the start of the first level
        if (opts.initial) {
            const openvdb::Vec3d du = opts.initial->displacement(toPoint3<D>(a));
            for (int i = 0; i < D; ++i)
                first[i] += du[i];
        }
        const double r = placement.toWorldLength((first - b).norm());
        result.landmarks.startMeanWorld += r / double(opts.sourceLandmarks.size());
        result.landmarks.startMaxWorld = std::max(result.landmarks.startMaxWorld, r);
    }
    result.landmarks.count = landmarks.source.size();
    // Automatic anchors (geometry/StillAnchors.h): held still at every level, each with weight
    // c_an / N, beside the automatic landmarks (each c_lm / K) at their levels.
    // The rigid limbs' points (geometry/RigidLimbs.h) beside them, each c_rl / M.
    LandmarkPairs<D> guided, anchored;
    if (!result.autoLandmarks.anchors.empty()) {
        const std::size_t k = landmarks.source.size(), n = result.autoLandmarks.anchors.size();
        guided = landmarks;
        guided.pairWeights.assign(k, Real(opts.landmarkWeight) / Real(k));
        anchored.weight = Real(opts.anchorWeight);
        for (const openvdb::Vec3d& w : result.autoLandmarks.anchors) {
            const Vec<D> a = toUnit<D>(placement, w);
            guided.source.push_back(a);
            guided.target.push_back(a);
            guided.pairWeights.push_back(Real(opts.anchorWeight) / Real(n));
            anchored.source.push_back(a);
            anchored.target.push_back(a);
        }
        const std::size_t m = result.autoLandmarks.limbSource.size();
        // Without limbs the anchors keep their one weight (runs bitwise as before).
        if (m > 0) anchored.pairWeights.assign(n, Real(opts.anchorWeight) / Real(n));
        for (std::size_t i = 0; i < m; ++i) {
            const Vec<D> a = toUnit<D>(placement, result.autoLandmarks.limbSource[i]);
            const Vec<D> b = toUnit<D>(placement, result.autoLandmarks.limbTarget[i]);
            const Real w = Real(opts.rigidLimbWeight) / Real(m);
            guided.source.push_back(a);
            guided.target.push_back(b);
            guided.pairWeights.push_back(w);
            anchored.source.push_back(a);
            anchored.target.push_back(b);
            anchored.pairWeights.push_back(w);
        }
    }
    const LandmarkPairs<D>& early = guided.source.empty() ? landmarks : guided;
    // The inner-distance term (energy/InnerDistanceTerm.h), from the paired extremities.
    InnerDistanceSamples<D> inner;
    if (opts.innerDistanceWeight > 0) {
        // The paired extremities, Omega units: the automatic landmarks, or beside given ones
        // (landmarkAnchors) the extremities that decided the anchors.
        LandmarkPairs<D> extremities;
        for (std::size_t k = 0; k < result.autoLandmarks.source.size(); ++k) {
            extremities.source.push_back(toUnit<D>(placement, result.autoLandmarks.source[k]));
            extremities.target.push_back(toUnit<D>(placement, result.autoLandmarks.target[k]));
        }
        result.innerDistance = innerDistanceSamples(unitSource, unitTarget, extremities,
                                                    result.autoLandmarks, opts, inner);
        if (observer.innerDistance) observer.innerDistance(result.innerDistance);
    }
    std::shared_ptr<const FieldSampler<D>> lastTarget;
    LevelSummary pending;
    // Distance tiers shared between levels (the coarse box and the band two levels down).
    ShapeSamplerCache<D> sourceTiers, targetTiers;
    const multiscale::ContextLevelBuilder<D> builder =
        [&](const multiscale::LevelContext<D>& context) {
            const int l = context.level;
            const Real h = std::ldexp(Real(1), -l);
            LevelSummary summary;
            summary.level = l;

            Clock::time_point t0 = Clock::now();
            multiscale::Level<D> level;
            // The two shapes' fields side by side: each scales only ~1.4x on two threads.
            auto buildSource = [&] {
                level.shape1 = buildShapeSampler<D>(unitSource, l, sourceSampler, sourceTiers);
            };
            auto buildTarget = [&] {
                level.shape2 = buildShapeSampler<D>(unitTarget, l, targetSampler, targetTiers);
            };
            detail::invokeBoth(opts.threaded, buildSource, buildTarget);
            level.surfacePoints = &unitSource.points;
            level.bendingFactor = noiseBendingFactor(
                pairSmoothingPasses(sourceSampler.fields.hessianSmoothingLength,
                                    targetSampler.fields.hessianSmoothingLength, h),
                opts.noiseBendingPasses);
            summary.bendingFactor = level.bendingFactor;
            if (l <= lastLandmarkLevel) {
                if (!early.source.empty()) level.landmarks = &early;
            } else if (!anchored.source.empty()) {
                level.landmarks = &anchored;
            }
            if (!inner.points.empty() && (opts.innerDistanceLevels == 0 ||
                                          l < opts.multiscale.minLevel + opts.innerDistanceLevels))
                level.innerDistance = &inner;
            summary.fieldSeconds = secondsSince(t0);

            t0 = Clock::now();
            // A band term lives on a simplex whose centroid x has |d1(x)| < sigma (direct half;
            // d1 does not depend on phi, so this region is exact) or |d2(phi(x))| < sigma
            // (inverse half; phi moves during the level, hence the margin).
            const Real sigma = opts.multiscale.energyAt(l).sigmaFactor * h;
            const Real reach1 = sigma;
            const Real reach2 = sigma + opts.refinementMarginCells * h;
            std::unique_ptr<multiscale::PiecewiseLinearInterpolator<D>> previous;
            Real lipschitz = 1;
            // The first level of a run from an earlier result: refine around its phi^{-1}(M2).
            const InitialDisplacement* initial =
                context.previousLattice ? nullptr : opts.initial.get();
            if (initial) lipschitz = Real(initial->lipschitz);
            if (context.previousLattice) {
                previous = std::make_unique<multiscale::PiecewiseLinearInterpolator<D>>(
                    *context.previousLattice);
                lipschitz =
                    lipschitzBound<D>(*context.previousLattice, *context.previousDisplacement);
            }
            // Centroids of the Kuhn simplices of a cell of side 1, from its origin.
            std::array<Vec<D>, SimplexLattice<D>::SIMPLICES> centroidOffsets;
            for (std::size_t p = 0; p < centroidOffsets.size(); ++p) {
                centroidOffsets[p].setZero();
                for (int m = 0; m <= D; ++m)
                    for (int a = 0; a < D; ++a)
                        if (KuhnSplit<D>::path()[p][m] & (1 << a)) centroidOffsets[p][a] += 1;
                centroidOffsets[p] /= Real(D + 1);
            }
            const FieldSampler<D>& d1 = *level.shape1;
            const FieldSampler<D>& d2 = *level.shape2;
            const NodeVectors<D>* uPrev = context.previousDisplacement;
            // A point x needs cells of side h if |d1(x)| < reach1 or |d2(phi_{l-1}(x))| <
            // reach2.
            // phi_{l-1}(x): the previous level's result, or the initial deformation at the
            // first level (the identity without one).
            auto previousPhi = [&](const Vec<D>& x) {
                Vec<D> y = x;
                if (previous) {
                    Vec<D> du;
                    if (previous->evaluate(*uPrev, x, du)) y += du;
                } else if (initial) {
                    const openvdb::Vec3d du = initial->displacement(toPoint3<D>(x));
                    for (int a = 0; a < D; ++a)
                        y[a] += du[a];
                }
                return y;
            };
            auto pointNeedsFine = [&](const Vec<D>& x) {
                Real d;
                if (!d1.sampleDistance(x, d) || std::abs(d) < reach1) return true;
                return !d2.sampleDistance(previousPhi(x), d) || std::abs(d) < reach2;
            };
            const RefinementPredicate<D> needsFine = [&](const Vec<D>& c, Real radius) {
                // Conservative test on the circumscribed ball (1-Lipschitz d1 and d2, phi
                // Lipschitz with constant `lipschitz`): false means no point of the cell needs
                // side h.
                Real d;
                bool near =
                    !d1.sampleDistance(c, d) || std::abs(d) < reach1 + radius + tierSlack(d1, c);
                if (!near) {
                    const Vec<D> y = previousPhi(c);
                    near = !d2.sampleDistance(y, d) ||
                           std::abs(d) < reach2 + lipschitz * radius + tierSlack(d2, y);
                }
                if (!near) return false;
                // The last split (a cell of side 2h into cells of side h): the band terms are
                // evaluated at simplex centroids (one-point quadrature), so the cell is split
                // only if a quadrature point of its own simplices or of its children's needs
                // side h. Whatever is not split then carries no band term at the start of the
                // level.
                const Real side = 2 * radius / std::sqrt(Real(D));
                if (side > 2.5 * h) return true;
                const Vec<D> origin = c - Vec<D>::Constant(side / 2);
                for (const Vec<D>& offset : centroidOffsets)
                    if (pointNeedsFine(origin + side * offset)) return true;
                for (int child = 0; child < (1 << D); ++child) {
                    Vec<D> childOrigin = origin;
                    for (int a = 0; a < D; ++a)
                        if (child & (1 << a)) childOrigin[a] += side / 2;
                    for (const Vec<D>& offset : centroidOffsets)
                        if (pointNeedsFine(childOrigin + (side / 2) * offset)) return true;
                }
                return false;
            };
            level.lattice = std::make_shared<SimplexLattice<D>>(
                buildAdaptiveLattice<D>(l, std::max(0, l - coarsestLevel), needsFine,
                                        context.previousLattice, opts.threaded));
            summary.latticeSeconds = secondsSince(t0);
            summary.lattice = summarize<D>(*level.lattice);
            if (observer.levelStart) observer.levelStart(summary);
            pending = summary;
            lastTarget = level.shape2;
            return level;
        };
    const multiscale::LevelObserver levelEnd = [&](const solver::Report& report) {
        pending.report = report;
        result.levels.push_back(pending);
        if (observer.levelEnd) observer.levelEnd(result.levels.back());
    };

    multiscale::InitialGuess<D> initialGuess;
    if (opts.initial) {
        initialGuess = [&](const SimplexLattice<D>& lattice) {
            const InitialDisplacement& initial = *opts.initial;
            NodeVectors<D> u = NodeVectors<D>::Zero(D, Eigen::Index(lattice.nodeCount()));
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, lattice.nodeCount()),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) {
                                      if (lattice.isBoundaryNode(i)) continue; // phi = Id
                                      const openvdb::Vec3d du = initial.displacement(
                                          toPoint3<D>(lattice.nodePosition(i)));
                                      for (int a = 0; a < D; ++a)
                                          u(a, Eigen::Index(i)) = du[a];
                                  }
                              });
            lattice.expand(u);
            const Real minDet = minDeterminant<D>(lattice, u);
            if (!(minDet > 0) || !u.allFinite()) {
                OPENVDB_THROW(InitialDeformationFolds,
                              "match: " << initial.description
                                        << " sampled at the nodes of the level " << lattice.level()
                                        << " lattice folds (min det D phi = " << minDet
                                        << " <= 0)");
            }
            return u;
        };
    }
    // One path through the levels: its result, level summaries and the residual on M1.
    struct Path
    {
        multiscale::MultiscaleResult<D> run;
        std::vector<LevelSummary> levels;
        SurfaceResidual residual;
        SurfaceResidual targetResidual; ///< MatchResult::targetResidual
        std::vector<Vec<D>> moved;      ///< phi(v), Omega units
        Real energy = INF;              ///< at the end of the finest level
    };
    const Real finestSigma =
        opts.multiscale.energy.sigmaFactor * std::ldexp(Real(1), -opts.multiscale.maxLevel);
    auto runPath = [&](const multiscale::MultiscaleOptions& levelOpts) {
        result.levels.clear();
        const multiscale::MultiscaleDriver<D> driver(levelOpts);
        Path path;
        path.run = driver.run(builder, observer.iteration, levelEnd, opts.threaded, interrupter,
                              initialGuess);
        if (result.levels.size() < path.run.reports.size()) {
            // Interrupted before a level started: no lattice was built for it.
            LevelSummary stopped;
            stopped.level = path.run.reports.back().level;
            stopped.report = path.run.reports.back();
            result.levels.push_back(stopped);
        }
        path.levels = std::move(result.levels);
        if (path.run.lattice) {
            path.residual =
                surfaceResidual<D>(*path.run.lattice, path.run.displacement, unitSource.points,
                                   lastTarget.get(), finestSigma, path.moved);
            path.targetResidual =
                targetResidual<D>(unitSource, path.moved, unitTarget.points,
                                  path.run.lattice->level(), finestSigma, opts.threaded);
        }
        if (path.run.isComplete()) path.energy = path.run.reports.back().energy;
        return path;
    };
    Path kept = runPath(opts.multiscale);

    // MatchOptions::secondPath: the coarse levels left part of M1 behind (or, with
    // secondPathTarget, of M2 unreached). The share a path leaves behind: of M1, and of M2 with
    // secondPathTarget.
    auto leftBehind = [&](double ofSource, double ofTarget) {
        return opts.secondPathTarget ? std::max(ofSource, ofTarget) : ofSource;
    };
    SecondPathSummary& second = result.secondPath;
    second.requested = opts.secondPath;
    second.threshold = opts.secondPathShare;
    second.farShare = kept.residual.farShare();
    second.targetFarShare = kept.targetResidual.farShare();
    second.target = opts.secondPathTarget;
    if (opts.secondPath) {
        if (opts.multiscale.minLevel >= opts.multiscale.maxLevel) {
            second.reason = "one level: no coarse level to run differently";
        } else if (!kept.run.isComplete() || !(kept.energy < INF)) {
            second.reason = "the first path did not complete";
        } else if (!(leftBehind(second.farShare, second.targetFarShare) > opts.secondPathShare)) {
            std::ostringstream r;
            r << "the first path reached M2: " << 100 * second.farShare
              << "% of M1 ended farther than sigma from it";
            if (opts.secondPathTarget)
                r << ", " << 100 * second.targetFarShare << "% of M2 from phi(M1)";
            r << " (threshold " << 100 * opts.secondPathShare << "%)";
            second.reason = r.str();
        } else {
            const Clock::time_point t0 = Clock::now();
            second.ran = true;
            const auto summary = [](const Path& path, Real factor) {
                PathSummary p;
                p.coarseVolumeFactor = factor;
                p.energy = path.energy;
                p.farShare = path.residual.farShare();
                p.targetFarShare = path.targetResidual.farShare();
                return p;
            };
            second.paths.push_back(summary(kept, opts.multiscale.coarseVolumeFactor));
            multiscale::MultiscaleOptions levelOpts = opts.multiscale;
            for (int k = 0; k < MAX_SECOND_PATHS; ++k) {
                levelOpts.coarseVolumeFactor *= SECOND_PATH_VOLUME_FACTOR;
                if (observer.secondPath) observer.secondPath(second);
                Path other = runPath(levelOpts);
                second.paths.push_back(summary(other, levelOpts.coarseVolumeFactor));
                // Strictly lower: on a tie (or an interrupted path) the earlier path stays.
                const bool complete = other.run.isComplete();
                const bool lower = complete && other.energy < kept.energy;
                if (lower) {
                    second.paths[second.kept].levels = std::move(kept.levels);
                    second.kept = second.paths.size() - 1;
                    kept = std::move(other);
                } else {
                    second.paths.back().levels = std::move(other.levels);
                }
                // Enough when this path reached M2, or was interrupted.
                const PathSummary& last = second.paths.back();
                if (!complete ||
                    !(leftBehind(last.farShare, last.targetFarShare) > opts.secondPathShare))
                    break;
            }
            second.seconds = secondsSince(t0);
            second.done = true;
            if (observer.secondPath) observer.secondPath(second);
        }
    }
    result.levels = std::move(kept.levels);
    result.lattice = kept.run.lattice;
    result.displacement = std::move(kept.run.displacement);

    result.deformedSource = source;
    if (result.lattice) {
        for (std::size_t i = 0; i < kept.moved.size(); ++i)
            result.deformedSource.points[i] = toWorld<D>(placement, kept.moved[i]);
        if (!landmarks.source.empty()) {
            const energy::LandmarkTerm<D> term(*result.lattice, landmarks);
            Real mean = 0, max = 0;
            term.residual(result.displacement, mean, max);
            result.landmarks.meanWorld = placement.toWorldLength(mean);
            result.landmarks.maxWorld = placement.toWorldLength(max);
        }
        if (!inner.points.empty()) {
            const energy::InnerDistanceTerm<D> term(*result.lattice, inner);
            Real mean = 0, beyond = 0;
            term.residual(result.displacement, mean, beyond);
            result.innerDistance.mean = mean;
            result.innerDistance.beyond = beyond;
        }
        result.residual = toMatchResidual(kept.residual, placement);
        result.targetResidual = toMatchResidual(kept.targetResidual, placement);
        for (auto it = result.levels.rbegin(); it != result.levels.rend(); ++it) {
            if (it->report.iterations > 0 || it->report.energy < INF) {
                result.minJacobian = it->report.minJacobian;
                break;
            }
        }
    }
    result.totalSeconds = secondsSince(start);
    return result;
}

template struct MatchResult<2>;
template struct MatchResult<3>;
template LatticeSummary summarize<2>(const SimplexLattice<2>&);
template LatticeSummary summarize<3>(const SimplexLattice<3>&);
template Real minDeterminant<2>(const SimplexLattice<2>&, const NodeVectors<2>&);
template Real minDeterminant<3>(const SimplexLattice<3>&, const NodeVectors<3>&);
template Real lipschitzBound<2>(const SimplexLattice<2>&, const NodeVectors<2>&);
template Real lipschitzBound<3>(const SimplexLattice<3>&, const NodeVectors<3>&);
template MatchResult<2> match<2>(const Surface<2>&, const Surface<2>&, const UnitBoxPlacement&,
                                 const MatchOptions&, const MatchObserver&,
                                 openvdb::util::NullInterrupter*);
template MatchResult<3> match<3>(const Surface<3>&, const Surface<3>&, const UnitBoxPlacement&,
                                 const MatchOptions&, const MatchObserver&,
                                 openvdb::util::NullInterrupter*);

} // namespace vdbmatch
