/// @file Match.h
/// @brief match(): the whole method of the paper on two shapes given in world space: placement
///        in Omega = (0,1)^d, per-level signed distances and adaptive lattices, the multiscale
///        descent, and the matching residual of the result.
///
/// For l = minLevel..maxLevel (h_l = 2^-l, sigma = 2 h_l, or 2 F h_l below the finest level with
/// MultiscaleOptions::coarseSigmaFactor F):
/// 1. the signed distances d1, d2 of the placed shapes are rebuilt at h_l (buildShapeSampler:
///    an exact narrow band at h_l over coarser tiers that cover all of Omega, so that d2 can be
///    sampled at phi(x) anywhere);
/// 2. the lattice is refined to cells of side h_l where a band term can live, i.e. near M1 and
///    near phi_{l-1}^{-1}(M2) (phi_{l-1} the result of the previous level, Id at minLevel):
///    a cell is fine if |d1| < sigma or |d2 o phi_{l-1}| < sigma + refinementMarginCells h_l at
///    a band quadrature point (simplex centroid) it would carry. Larger cells are split when the
///    ball around their centre may reach that region (1-Lipschitz distances, the Lipschitz
///    constant of phi_{l-1}, lipschitzBound); the last split, of a cell of side 2h into cells of
///    side h, samples the centroids of the cell's own simplices and of its children's, so that
///    cells of side h cover the bands and little more (3.4x fewer than the ball test at level 7
///    of the starfish pair, docs/performance.md). The first region is exact: the direct band
///    does not move. The margin of the second allows phi to move during the level;
///    EnergyTerms::coarseBandSimplices (report.json) counts the band simplices that fell
///    outside the fine region anyway (0 on the bundled pairs). Elsewhere cells grow by 2:1 up to
///    the side h_{minLevel} of the first level (buildAdaptiveLattice). No new cell is larger than
///    the cell of level l-1 that contains it, so prolongation is exact and det D phi > 0 carries
///    over;
/// 3. the descent of the paper runs on that lattice from the prolongated phi_{l-1}
///    (MultiscaleDriver, Descent, H1Metric).
/// At the end, the source surface's vertices v are moved by phi and the residual |d2(phi(v))|
/// is measured with the finest target sampler.
///
/// Spaces: the input surfaces and every output length marked "world" are in the inputs' world
/// space; the lattice, the displacement and the fields are in Omega units
/// (unit = placement.scale * (world - placement.worldOrigin), UnitBox.h).
/// @see paper sec:numerics, tab:parameters, eq:Esym, eq:Ecomparison
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/RigidLimbs.h>
#include <vdbmatch/geometry/StillAnchors.h>
#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/geometry/SurfaceNoise.h>
#include <vdbmatch/geometry/UnitBox.h>
#include <vdbmatch/lattice/SimplexLattice.h>
#include <vdbmatch/multiscale/MultiscaleDriver.h>

#include <openvdb/Exceptions.h>
#include <openvdb/util/NullInterrupter.h>

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace vdbmatch {

/// Default stopping rule of match() (docs/numerics.md): a level ends when the energy fell by
/// less than DEFAULT_MATCH_ENERGY_TOLERANCE / 4^(maxLevel - l) of |E - C| over 5 iterations
/// (DescentOptions::energyTolerance, C = Energy::constantOffset, so that the directional energy
/// stops at the same convergence as the symmetric one; MultiscaleOptions::toleranceCoarsening
/// makes the coarse levels, where iterations are cheap, converge further). Measured on the
/// accuracy benchmark (docs/performance.md): closer to the true correspondence than the former
/// default (1e-3 at every level, constant included). In 3D the finest level also ends by the
/// surface test (DEFAULT_MATCH_SURFACE_TOLERANCE_3D). The settle test
/// (DescentOptions::settleTolerance, --settle-tolerance) stops much earlier and is off: on the
/// benchmark it lost accuracy on 5 of 6 pairs.
constexpr double DEFAULT_MATCH_ENERGY_TOLERANCE = 1e-3;
/// Default c_lm of the landmark term (energy/LandmarkTerm.h): docs/numerics.md "Landmarks".
constexpr double DEFAULT_LANDMARK_WEIGHT = 1000;
/// Defaults of the inner-distance term (MatchOptions::innerDistanceWeight): docs/numerics.md
/// "The inner distance". On in 2D, where it lowered the benchmark's error (five runs: geometric
/// means 0.955 and |psi o phi - Id| 0.871 against the term off, then 0.976 and 1.045 of that
/// with the fields continued from each side of a gap); off in 3D, where it did not (the swung
/// leg unchanged, the tail swing 8% worse) and its fields cost a third of a run.
constexpr double DEFAULT_INNER_DISTANCE_WEIGHT_2D = 1000;
constexpr double DEFAULT_INNER_DISTANCE_WEIGHT_3D = 0;
constexpr double DEFAULT_INNER_DISTANCE_TOLERANCE = 0.01;
/// MatchOptions::innerDistanceRatio: 1, every vertex of M1 in the inner-distance term. Keeping
/// only the vertices whose second-nearest extremity is 1.5-3 times as far as the nearest was
/// measured and is not the default (five runs of the 2D benchmark: no variant better on every
/// pair; docs/numerics.md "The inner distance", *Which points*).
constexpr double DEFAULT_INNER_DISTANCE_RATIO = 1;
constexpr int DEFAULT_INNER_DISTANCE_LEVEL_2D = 8;
constexpr int DEFAULT_INNER_DISTANCE_LEVEL_3D = 7;
constexpr int MAX_INNER_DISTANCE_LEVEL = 9;    ///< in 2D; validate(dim) checks 3D against:
constexpr int MAX_INNER_DISTANCE_LEVEL_3D = 8; ///< (2^8 + 1)^3 nodes per extremity's field
/// Default most automatic anchors (StillAnchorOptions::count, --anchor-count) in 2D and 3D:
/// about the same spacing on a 3D surface as on a 2D outline (0.024-0.029 of the box on the
/// benchmark's 3D shapes, about 0.027 on the 2D figure). 300 rather than 100 in 3D lowered the
/// error on all five 3D pairs where anchors act (docs/numerics.md "The count and the weight in
/// 3D"); in 2D 300 is worse.
constexpr std::size_t DEFAULT_ANCHOR_COUNT_2D = 100;
constexpr std::size_t DEFAULT_ANCHOR_COUNT_3D = 300;
/// Default c_an, the total weight of the automatic anchors (MatchOptions::anchorWeight), in 2D
/// and 3D: each anchor weighs c_an / count, 10 in 2D and 100 in 3D (docs/numerics.md
/// "Automatic anchors", "The count and the weight in 3D").
constexpr double DEFAULT_ANCHOR_WEIGHT_2D = 1000;
constexpr double DEFAULT_ANCHOR_WEIGHT_3D = 30000;
/// The automatic anchors act only when the motion is an articulation: some extremity stays (its
/// pair lies within the anchor radius) and moves at most this fraction of the extremity that
/// moves most. Extremities that all move alike (a twist of the body, a turn of the whole shape)
/// leave coinciding parts that may have slid along themselves: docs/numerics.md "Automatic
/// anchors". On the benchmark's articulations the least-moving extremity moves 0-0.16 of the
/// most (its pair's jitter; five placements), on its twists, swirls and stretches 0.28-0.93.
/// Until 2026-12-02 the ratio was 0.5, which the torso twist crossed when the placement moved
/// by 0.5% (its tail, near the twist's axis, moves 0.35-0.86 of the most as its extremity
/// falls on the lattice), and its error doubled.
constexpr double ANCHOR_STILL_RATIO = 0.25;
/// When a rigid limb is sought (MatchOptions::rigidLimbMinMotion), every extremity that moved
/// farther than this fraction of the largest motion is a limb too, so that two limbs swung alike
/// are held alike (docs/numerics.md "Rigid limbs").
constexpr double RIGID_LIMB_MOTION_RATIO = 0.5;
/// Default c_rl, the total weight of the rigid limbs' points (MatchOptions::rigidLimbWeight), in
/// 2D and 3D: 20 points of one limb weigh 500 each, five times an anchor (docs/numerics.md
/// "Rigid limbs"; in 2D since 2026-12-02, when the fit learnt to start from more than the
/// principal axes).
constexpr double DEFAULT_RIGID_LIMB_WEIGHT = 1e4;
/// Default MatchOptions::rigidLimbAnchorRadius in 3D: half the anchors' radius when a rigid limb
/// is held (docs/numerics.md "Rigid limbs").
constexpr double DEFAULT_RIGID_LIMB_ANCHOR_RADIUS_3D = 0.015;

/// Default MatchOptions::anchorNoiseFactor in 3D: the anchors' tolerance is at least this times
/// the shapes' correlated noise (correlatedNoise(), about 1.6 times its standard deviation), so
/// about 2.5 standard deviations. A noisy scan then still coincides with the source where it
/// did not move; white noise and noise-free shapes keep the fixed tolerance. 0 in 2D, where
/// the outlines' coincident share under noise stays larger and the rule gained nothing on the
/// benchmark's figures (docs/numerics.md "The anchors' tolerance follows the noise").
constexpr double DEFAULT_ANCHOR_NOISE_FACTOR_3D = 1.6;
constexpr double DEFAULT_MATCH_TOLERANCE_COARSENING = 4;
constexpr double DEFAULT_MATCH_SETTLE_TOLERANCE = 0;
/// Default surface test (MultiscaleOptions::surfaceTolerance, --surface-tolerance) at the finest
/// level: it ends when the source surface moved by less than 0.02 h over 5 iterations (path
/// length of the mean over M1's vertices). In 3D, where the default levels are 4..8, the finest
/// level then takes 8 iterations instead of 84 on the starfish pair (whole match 0.54x) and the
/// accuracy benchmark at 4..8 is unchanged within 1% (docs/performance.md). In 2D (4..9) it cost
/// 15% correspondence error on one pair, so it is off there.
constexpr double DEFAULT_MATCH_SURFACE_TOLERANCE_3D = 0.02;
constexpr double DEFAULT_MATCH_SURFACE_TOLERANCE_2D = 0;
constexpr int DEFAULT_MATCH_SURFACE_LEVELS = 1;
/// Default MultiscaleOptions::surfaceFromLevel (--surface-from-level): 0, the surface test
/// ends the finest level only. With 7 it also ends level 7 of the default levels 4..8 once the
/// surface has settled (starfish: 19 iterations instead of 78, the whole match 27.9 s instead of
/// 35.6 s); on the accuracy benchmark at 4..8 the mean error moved by -1%..+6% but
/// |psi o phi - Id| by -13%..+27%; repeated with a last-digit control of each variant, the mean
/// error rose on 5 of 6 pairs (1-6%) and |psi o phi - Id| on 4 (9-24%) on both runs, so it is
/// an option, not the default (docs/performance.md).
/// Ending level 6 the same way (7 at levels 4..7) cost 6-19% correspondence error: the coarser
/// levels set the correspondence in their slow tail (docs/numerics.md).
constexpr int DEFAULT_MATCH_SURFACE_FROM_LEVEL = 0;
/// MatchOptions::secondPath: a second path runs when more than this share of M1's vertices ended
/// farther than sigma of the finest level from M2 (|d2(phi(v))| > 2 h: part of the source left
/// behind, outside the band where the finest level can still pull it; docs/numerics.md "Second
/// path").
constexpr double DEFAULT_SECOND_PATH_SHARE = 0.01;
/// Each further path's MultiscaleOptions::coarseVolumeFactor, times the previous path's.
constexpr double SECOND_PATH_VOLUME_FACTOR = 4;
/// Paths run after the first one at most (MatchOptions::secondPath): 4x, then 16x c_vol.
constexpr int MAX_SECOND_PATHS = 2;
/// Default MultiscaleOptions::coarseMembraneFactor (--coarse-membrane-factor), an addition to the
/// paper: the levels below the finest weigh the membrane term by 3 c_mem. The coarse levels set
/// the tangential correspondence, and a stiffer membrane there keeps it closer to an isometry;
/// the finest level, with the paper's c_mem, lets stretched shapes stretch. Measured on the
/// correspondence benchmark (bench/bench_accuracy.sh --resampled; docs/numerics.md,
/// docs/results.md): mean |phi(v) - g(v)| -14..-31% on the articulated, swirled and twisted pairs,
/// +6% and +3% on the head turn and tail swing, +16% on the 3D stretch. 4 helps the same pairs a
/// little more but sends the figure's squat into another minimum (error 1.85x, surface not fitted).
constexpr double DEFAULT_MATCH_COARSE_MEMBRANE_FACTOR = 3;
/// Default EnergyParameters::membraneSaturation of match() (--membrane-saturation), an addition to
/// the paper (math/Saturation.h): in 3D the membrane densities at the first
/// DEFAULT_MATCH_MEMBRANE_SATURATION_LEVELS levels are psi_s(W) = s log(1 + W/s), s = 0.1. On the
/// correspondence benchmark (docs/results.md, Membrane saturation) it lowered the mean error on 7
/// of the 8 3D pairs (geometric mean of the ratios 0.90: the swung leg -37%, the raised arm
/// -17%, the tail swing -13%; the 3D stretch +6%), but on only 3 of the 8 2D pairs (the star
/// jump +14%, the articulated figure +10%), so 2D keeps the paper's density.
constexpr double DEFAULT_MATCH_MEMBRANE_SATURATION_3D = 0.1;
constexpr double DEFAULT_MATCH_MEMBRANE_SATURATION_2D = 0;
/// Default MultiscaleOptions::membraneSaturationLevels of match() (--membrane-saturation-levels).
/// match() counts these levels from coarsestLevel, the first of the requested range, so that a run
/// resumed or refined from an earlier result (--init) saturates no level the earlier run did not.
constexpr int DEFAULT_MATCH_MEMBRANE_SATURATION_LEVELS = 2;
/// Default MultiscaleOptions::metricTauFactor of match() in 2D (--metric-tau): the weight of the
/// descent's H1 metric, tau = 2 sigma^2 instead of solver::DEFAULT_METRIC_TAU_FACTOR = 1/2 (3D and
/// --preset paper; the paper says "weighted H^1 metric" and gives no weight). It changes the path
/// of the descent, not the energy: a smoother descent direction moves the limbs more as a whole.
/// Measured on the eight 2D pairs of the correspondence benchmark over five runs (docs/numerics.md
/// "Metric weight"): mean |phi(v) - g(v)| lower on 6 of 8 (geometric mean of the ratios 0.967; the
/// star jump -12%, the articulated figure -7%; the squat +1.5%, the stretch +1%), |psi o phi - Id|
/// 0.89, time 0.89. In 3D the same change was a wash (error 1.006, |psi o phi - Id| 0.994) and
/// costs CG iterations, so 3D keeps 1/2.
constexpr double DEFAULT_MATCH_METRIC_TAU_2D = 2;
/// Default relative residual of the metric's CG solves in match(): the descent direction need not
/// be exact (12 instead of 31 CG iterations per solve at level 7, same residual and energy).
constexpr double DEFAULT_MATCH_METRIC_TOLERANCE = 1e-2;
/// Absolute floor of the H1 gradient norm (DescentOptions::gradientTolerance): a gradient below
/// it is rounding, e.g. when source and target are the same shape (E ~ 1e-17). Real matches
/// start with norms of 1e1..1e3 and stop, relatively, far above it.
constexpr double DEFAULT_MATCH_GRADIENT_FLOOR = 1e-10;

/// Default extra margin of the fine region, in cells of side h_l (see the file comment): the
/// band moves by up to about one cell during a level's descent.
constexpr double DEFAULT_REFINEMENT_MARGIN_CELLS = 1.0;
/// Largest accepted margin: wider ones refine (nearly) all of Omega at the finest level.
constexpr double MAX_REFINEMENT_MARGIN_CELLS = 64.0;

/// Finest levels accepted by match(), checked before anything is allocated. Peak memory grows
/// about 4x per level in 3D (0.8 GB at level 8 for the bundled starfish pair, so ~3 GB at 9) and
/// 2x per level in 2D; the limits keep a match within a few GB.
constexpr int MAX_MATCH_LEVEL_3D = 9;
constexpr int MAX_MATCH_LEVEL_2D = 12;
/// Largest finest level for dimension @a dim.
inline int
maxMatchLevel(int dim)
{
    return dim == 2 ? MAX_MATCH_LEVEL_2D : MAX_MATCH_LEVEL_3D;
}

/// A start of the descent other than phi = Id: the displacement u = phi - Id of an earlier
/// result (vdb_match match --init, io/InitialDeformation.h). match() samples it at the nodes of
/// the first level's lattice (exact where that lattice nests in the pieces on which u is
/// linear), sets the boundary nodes to 0 and the hanging nodes to their constraint values, and
/// refines that level around phi^{-1}(M2) as it does for later levels.
struct InitialDisplacement
{
    /// u(x) at x in Omega, Omega units (2D: z is 1/2 and ignored, the result's z is unused).
    /// Called concurrently. Signature: openvdb::Vec3d(const openvdb::Vec3d& xUnit).
    std::function<openvdb::Vec3d(const openvdb::Vec3d&)> displacement;
    /// An upper bound of the spectral norm of D phi over Omega (>= 1).
    double lipschitz = 1;
    /// What it is, for messages ("--init 'out/deformation.vdb'").
    std::string description = "the initial deformation";
};

/// Thrown by match() when MatchOptions::initial, sampled at the nodes of the first lattice,
/// folds (det D phi <= 0 on a simplex). A ValueError, so that callers that do not distinguish it
/// see the same exception as before; a caller with a fallback (vdb_match match --warm-start
/// starts from the identity instead) catches it alone.
struct InitialDeformationFolds : public openvdb::ValueError
{
    using openvdb::ValueError::ValueError;
};

struct MatchOptions
{
    /// Levels, energy parameters and kind, metric and descent options (tab:parameters).
    multiscale::MultiscaleOptions multiscale = multiscale::MultiscaleOptions::defaults(3);
    /// Placement margin on each side of the shapes' common box, Omega units, [0, 0.5).
    double margin = DEFAULT_UNIT_BOX_MARGIN;
    /// Signed-distance tiers and shape-field options (tau, Hessian smoothing) per level.
    ShapeSamplerOptions sampler;
    /// Extra width of the fine region, in cells (>= 0).
    double refinementMarginCells = DEFAULT_REFINEMENT_MARGIN_CELLS;
    /// Coarsest cells: side h_{coarsestLevel}; <= 0 selects multiscale.minLevel.
    int coarsestLevel = 0;
    /// Start of the first level (multiscale.minLevel) instead of phi = Id; null: the identity.
    std::shared_ptr<const InitialDisplacement> initial;
    /// Optional landmark pairs, world units of the inputs (2D: z ignored), the same count: a
    /// soft term c_lm / K sum |phi(a_k) - b_k|^2 added at every level (energy/LandmarkTerm.h,
    /// an addition to the paper's energy). Empty: none.
    std::vector<openvdb::Vec3d> sourceLandmarks, targetLandmarks;
    /// c_lm of the landmark term, Omega units (>= 0).
    double landmarkWeight = DEFAULT_LANDMARK_WEIGHT;
    /// Automatic landmarks, an addition to the paper (docs/numerics.md "Automatic landmarks"):
    /// when no landmarks are given, the extremities of the two shapes (geometry/Extremities.h),
    /// paired by their inner distances (geometry/ExtremityMatching.h), are the landmarks of the
    /// first autoLandmarkLevels levels only: they choose which limb goes where at the coarse
    /// levels, and the finer levels follow the shape energy alone. When the extremities cannot
    /// be paired, or move less than autoLandmarkMinMotion, or the run starts from `initial`,
    /// the match runs without (MatchResult::autoLandmarks says why). On in defaults(), off in
    /// paper().
    bool autoLandmarks = false;
    /// Levels, from the first, at which the automatic landmarks act (>= 1).
    int autoLandmarkLevels = 2;
    /// The automatic landmarks act only when some pair lies farther apart than this many sigma
    /// of the first level (>= 0; 0, the default: whenever the extremities are paired). Until
    /// 2026-11-27 it was 1: a smaller motion was left to the shape energy, which the benchmark's
    /// legs spread 25 degrees (0.997 sigma) showed to be fragile (docs/numerics.md).
    double autoLandmarkMinMotion = 0;
    /// Automatic anchors, an addition to the paper (docs/numerics.md "Automatic anchors"): when
    /// the automatic landmarks act (or landmarks are given, with landmarkAnchors) and the
    /// motion is an articulation (ANCHOR_STILL_RATIO),
    /// points of M1 around which M2 coincides with it (geometry/StillAnchors.h) are held still,
    /// phi(x) = x, by a soft term of total weight anchorWeight (each anchor anchorWeight / count)
    /// at every level: what the motion left in place stays, instead of sliding along its own
    /// surface toward the moving limb. On in defaults(), off in paper().
    bool autoAnchors = false;
    /// With autoAnchors and given landmarks (sourceLandmarks), an addition to the paper: the
    /// extremities are still found and paired, not as landmarks (the given ones replace them)
    /// but to tell an articulation, and the anchors then act at every level beside the given
    /// landmarks, with the inner-distance term from those extremities (innerDistanceWeight).
    /// Without it, landmarks given by the caller turned the anchors off, and the benchmark's
    /// true landmarks (five points and their images under g, make_pairs.py) matched its swung
    /// limbs 2-2.6x worse than none
    /// (docs/numerics.md "Automatic anchors"). On in defaults(), off in paper().
    bool landmarkAnchors = false;
    /// Tolerance, radius and count (Omega units); paper(dim) and defaults(dim) set the count per
    /// dimension (DEFAULT_ANCHOR_COUNT_2D/3D), as they set anchorWeight.
    StillAnchorOptions anchorOptions;
    /// The anchors' tolerance follows the noise, an addition to the paper: it is the larger of
    /// anchorOptions.tolerance and this factor times the hypotenuse of the two shapes'
    /// correlatedNoise() (geometry/SurfaceNoise.h), from the readings the Hessian smoothing
    /// takes (so it acts only with hessianNoiseFactor and hessianLatticeNoiseFactor > 0). Noise
    /// correlated over a few vertices keeps a scan off the source by its amplitude where
    /// nothing moved, so that no patch of it lies within the fixed tolerance. >= 0; 0: off
    /// (paper()); defaults(): DEFAULT_ANCHOR_NOISE_FACTOR_3D in 3D, 0 in 2D.
    double anchorNoiseFactor = 0;
    double anchorWeight = DEFAULT_ANCHOR_WEIGHT_3D; ///< c_an >= 0, Omega units (defaults(dim))
    /// Rigid limbs, an addition to the paper (docs/numerics.md "Rigid limbs"): when the anchors
    /// act, each paired extremity that moved is the tip of a limb carried rigidly, without a
    /// turn about its own axis (geometry/RigidLimbs.h); count points of each limb that the fit
    /// finds rigid are held at every level at their images, beside the anchors, each with
    /// weight rigidLimbWeight / (their number). A round limb's turn about its axis is what no
    /// shape term sees (docs/results.md "The swung leg turns about its own axis"), and a limb
    /// swung far is carried whole from the coarse levels on. c_rl = 0: off (paper());
    /// defaults(): DEFAULT_RIGID_LIMB_WEIGHT.
    double rigidLimbWeight = 0;
    /// Limbs only when some extremity moved farther than this many sigma of the first level
    /// (>= 0): a limb nearer than the first band is found by the match term from the start; one
    /// beyond it is carried far by the coarse levels, which is where a round limb turns. Then
    /// every extremity that moved farther than that, or than RIGID_LIMB_MOTION_RATIO of the
    /// largest motion, is a limb (two limbs swung alike are held alike).
    double rigidLimbMinMotion = 1;
    /// When a rigid limb is held, the anchors are sought again with this patch radius (Omega
    /// units), if smaller than anchorOptions.radius: a limb swung beyond the first band drags
    /// the skin next to its joint, and smaller patches put anchors nearer the joint. They are
    /// sought with a tolerance of at least anchorNoiseFactor times the hypotenuse of the two
    /// shapes' whole lattice readings, white noise included (on a white-noise scan the skin next
    /// to the joint lies off the source by more than the fixed tolerance). >= 0; 0: the anchors
    /// keep their radius (paper(), defaults(2)); defaults(3): DEFAULT_RIGID_LIMB_ANCHOR_RADIUS_3D.
    double rigidLimbAnchorRadius = 0;
    /// Reach, fit, count and rigid segments (Omega units; minMotion is set from
    /// rigidLimbMinMotion). The segments (RigidLimbOptions::segmentTo > 0, docs/numerics.md
    /// "Rigid segments") are on in 2D and off in 3D (paper(3), defaults(3)).
    RigidLimbOptions rigidLimbOptions;
    /// Inner-distance term, an addition to the paper (docs/numerics.md "The inner distance"):
    /// when the extremities are paired (the automatic landmarks, or beside given landmarks with
    /// landmarkAnchors) and the anchors act (an articulation: a stretch or a twist
    /// changes the inner distance itself), c_F times the mean over M1 of
    /// max(|F2_k(phi(x)) - F1_k(x)| - tau, 0)^2, F1_k and F2_k the inner distances from the
    /// paired extremity k of each shape, k the one nearest to x in M1 (geometry/InnerDistance.h,
    /// energy/InnerDistanceTerm.h), at the first innerDistanceLevels levels. c_F = 0: off
    /// (paper(), and defaults(3)); defaults(2): DEFAULT_INNER_DISTANCE_WEIGHT_2D.
    double innerDistanceWeight = 0;
    double innerDistanceTolerance = DEFAULT_INNER_DISTANCE_TOLERANCE; ///< tau >= 0, Omega units
    /// >= 1: only the vertices x of M1 whose second-nearest extremity is at least this many
    /// times as far as the nearest (F1 inside M1) are in the term; 1: every vertex. Where two
    /// extremities are about as near (the body between the limbs, a hand hanging by the hip),
    /// an articulation changes the distance to either.
    double innerDistanceRatio = DEFAULT_INNER_DISTANCE_RATIO;
    /// Level of F's lattice; <= 0: DEFAULT_INNER_DISTANCE_LEVEL_2D/3D.
    int innerDistanceLevel = 0;
    /// Levels, from the first, at which the term acts (>= 0); 0: every level.
    int innerDistanceLevels = 0;
    /// Second path, an addition to the paper (docs/numerics.md "Second path"): when more than
    /// secondPathShare of M1's vertices end farther than sigma of the finest level from M2 (a
    /// part of the source left behind by the coarse levels, a local minimum the finest level
    /// cannot leave), the levels run again from the start with SECOND_PATH_VOLUME_FACTOR times
    /// the coarse volume factor (multiscale.coarseVolumeFactor), and once more with that factor
    /// again if that path too leaves more than secondPathShare behind (MAX_SECOND_PATHS). The
    /// result whose finest level ends at the lowest energy is kept. The finest level's
    /// functional is the same on every path, so the choice is the paper's own criterion. Needs
    /// two levels or more. On in defaults(), off in paper().
    bool secondPath = false;
    double secondPathShare = DEFAULT_SECOND_PATH_SHARE; ///< in [0, 1]
    /// With secondPath, look at M2 too (`--second-path-target`, off by default and in paper();
    /// docs/numerics.md "Target residual"): another path also runs when more than
    /// secondPathShare of M2's vertices end farther than sigma from phi(M1)
    /// (MatchResult::targetResidual: a part of the target the first path does not reach), and
    /// a further one while the last path leaves more than that share of either shape. Not a
    /// default: on the benchmark it changes one pair, whose target it then reaches at a higher
    /// correspondence error.
    bool secondPathTarget = false;
    /// Noise-adaptive Hessian smoothing, an addition to the paper (docs/numerics.md
    /// "Noise-adaptive Hessian smoothing"): each shape's Hessian of d is smoothed over
    /// hessianNoiseFactor times the shape's own vertex noise (geometry/SurfaceNoise.h, Omega
    /// units), which sets sampler.fields.hessianSmoothingLength per shape: a scan's fine levels
    /// are smoothed; the benchmark's noise-free meshes and outlines and the bundled level sets
    /// get no pass and run bitwise as without. >= 0; 0: off (paper()); defaults():
    /// NOISE_SMOOTHING_LENGTH_FACTOR.
    double hessianNoiseFactor = 0;
    /// The lattice reading of the noise, an addition to the paper (docs/numerics.md
    /// "Correlated noise"): each shape's Hessian smoothing length is the larger of
    /// hessianNoiseFactor times its vertex noise and this factor times
    /// latticeSurfaceNoise() at LATTICE_NOISE_LEVEL (geometry/SurfaceNoise.h), which reads
    /// noise correlated over a few vertices at its amplitude where the vertex reading falls.
    /// Acts only with hessianNoiseFactor > 0. >= 0; 0: off (paper()); defaults():
    /// LATTICE_NOISE_SMOOTHING_FACTOR_3D in 3D, 0 in 2D.
    double hessianLatticeNoiseFactor = 0;
    /// Bending weight on noisy shapes, an addition to the paper: at each level c_bend is
    /// multiplied by noiseBendingFactor(n, noiseBendingPasses), n the larger of the two shapes'
    /// noise smoothing passes there (lengthSmoothingPasses of their Hessian smoothing lengths,
    /// set by hessianNoiseFactor). A smoothed Hessian is a less certain shape operator; where
    /// none is smoothed (noise-free inputs) the weight is the paper's, bitwise. >= 0; 0: off
    /// (paper()); defaults(): DEFAULT_NOISE_BENDING_PASSES.
    double noiseBendingPasses = 0;
    bool threaded = true;

    /// tab:parameters for dimension 2 or 3, with the DEFAULT_MATCH_* stopping rule and
    /// DEFAULT_MATCH_METRIC_TOLERANCE: paper(dim) plus the surface test, the coarse membrane
    /// factor, the membrane saturation at the first levels, automatic landmarks and anchors, and
    /// the second path.
    static MatchOptions defaults(int dim);
    /// The paper's experiment (`--preset paper`): tab:parameters and its levels (4..8 in 3D,
    /// 4..9 in 2D, sigma = 2h), and none of our additions that change the result (no surface
    /// test, no landmarks, no second path). The paper gives no stopping rule, metric weight or
    /// refinement margin: those are ours, as in defaults().
    static MatchOptions paper(int dim);
    /// Throws openvdb::ValueError naming the first invalid field.
    void validate() const;
    /// validate(), and the levels within 1..maxMatchLevel(dim).
    void validate(int dim) const;
};

/// The lattice of one level, compared with the dense lattice of the same h.
struct LatticeSummary
{
    std::size_t cells = 0, simplices = 0, nodes = 0, unknowns = 0, hangingNodes = 0;
    std::size_t denseNodes = 0; ///< (2^l + 1)^d
    std::vector<std::size_t> cellsPerLog2Size;
};

/// One level of a match.
struct LevelSummary
{
    int level = 0;
    LatticeSummary lattice;
    solver::Report report;
    double bendingFactor = 1;  ///< c_bend's factor at this level (noiseBendingFactor())
    double fieldSeconds = 0;   ///< signed distances and shape fields of both shapes
    double latticeSeconds = 0; ///< adaptive lattice
};

/// |phi(a_k) - b_k| over the landmark pairs (MatchOptions::sourceLandmarks), before (phi = the
/// start of the first level) and after the match.
struct LandmarkResidual
{
    std::size_t count = 0;
    double startMeanWorld = 0, startMaxWorld = 0; ///< world units, at the start
    double meanWorld = 0, maxWorld = 0;           ///< world units, at the end
};

/// What MatchOptions::autoLandmarks found.
struct AutoLandmarkSummary
{
    /// autoLandmarks was set and no landmarks were given, or landmarks were given and
    /// MatchOptions::landmarkAnchors asked for the anchors (then used is false: the extremities
    /// only decide the anchors and the inner-distance term)
    bool requested = false;
    bool used = false;    ///< the pairs acted as landmarks
    std::string reason;   ///< why not, when requested && !used
    bool paired = false;  ///< the extremities were paired (used, or every pair moved too little)
    double maxMotion = 0; ///< largest |a_k - b_k| of the pairs, Omega units
    double minMotion = 0; ///< the threshold, autoLandmarkMinMotion sigma of the first level
    std::size_t sourceExtremities = 0, targetExtremities = 0;
    double distortion = 0;      ///< of the pairing (ExtremityPairing::distortion)
    std::size_t candidates = 0; ///< pairings within the tolerance (ExtremityPairing::candidates)
    /// The paired extremities, world units (2D: z = 0), row k of each: the landmarks when used,
    /// else (beside given landmarks) what decided the anchors and the inner-distance term; empty
    /// when not paired, or when the pairs moved too little to act (autoLandmarkMinMotion).
    std::vector<openvdb::Vec3d> source, target;
    int lastLevel = 0; ///< the landmarks act at the levels up to this one
    /// Automatic anchors (MatchOptions::autoAnchors), world units (2D: z = 0); they act at
    /// every level. Empty when not requested, when the landmarks do not act, when no extremity
    /// stays (no pair closer than the anchor radius: a turn of the whole shape), when the
    /// extremities move alike (ANCHOR_STILL_RATIO: a twist), or when M1 and M2 coincide nowhere
    /// (anchorReason says which of the last three).
    std::vector<openvdb::Vec3d> anchors;
    std::string anchorReason;
    double anchorCoincidentShare = 0; ///< StillAnchors::coincidentShare() (both shapes)
    /// The tolerance the anchors were sought with (Omega units; MatchOptions::anchorNoiseFactor,
    /// and for the nearer anchors of a held limb MatchOptions::rigidLimbAnchorRadius); 0 when
    /// they were not sought.
    double anchorTolerance = 0;
    /// Rigid limbs (MatchOptions::rigidLimbWeight > 0, with the anchors): what the fit found of
    /// each moving limb (Omega units, degrees), and the points held at every level with their
    /// images, world units (2D: z = 0).
    /// RigidLimbFit::extremity is the row of source/target.
    std::vector<RigidLimbFit> limbs;
    double limbMinMotion = 0; ///< the threshold (Omega units): rigidLimbMinMotion sigma of the
                              ///< first level, or less (MatchOptions::rigidLimbMinMotion)
    /// The anchors' patch radius (StillAnchorOptions::radius, Omega units): the option's, or
    /// MatchOptions::rigidLimbAnchorRadius when a rigid limb is held; 0 when not sought.
    double anchorRadius = 0;
    std::vector<openvdb::Vec3d> limbSource, limbTarget;
    double seconds = 0;
};

/// What MatchOptions::innerDistanceWeight did: |F2(phi(x)) - F1(x)| over the vertices x of M1
/// in the term (MatchOptions::innerDistanceRatio), weighted by their shares of M1's measure
/// (Omega units).
struct InnerDistanceSummary
{
    bool requested = false; ///< innerDistanceWeight > 0
    bool used = false;      ///< the term acted
    std::string reason;     ///< why not, when requested && !used
    double weight = 0, tolerance = 0;
    int level = 0;          ///< of F's lattice
    double ratio = 0;       ///< MatchOptions::innerDistanceRatio
    std::size_t points = 0; ///< vertices of M1 in the term
    double share = 0;       ///< their share of M1's measure
    double startMean = 0;   ///< at phi = Id
    double startBeyond = 0; ///< share beyond the tolerance at phi = Id
    double mean = 0;        ///< at the end
    double beyond = 0;      ///< share beyond the tolerance at the end
    double seconds = 0;     ///< F1 and F2
};

/// Distances of one shape's vertices to the other: |d2(phi(v))| over the vertices v of M1
/// (MatchResult::residual), or dist(y, phi(M1)) over the vertices y of M2
/// (MatchResult::targetResidual).
struct MatchResidual
{
    double meanWorld = 0, maxWorld = 0; ///< world units
    double meanUnit = 0, maxUnit = 0;   ///< Omega units (fraction of the unit box)
    std::size_t samples = 0;
    /// Share of the samples farther than sigma of the finest level (> 2 h).
    double farShare = 0;
    /// targetResidual: samples counted at TARGET_RESIDUAL_BAND_CELLS cells, farther in truth
    /// (meanUnit and maxUnit are then lower bounds); 0 for residual.
    std::size_t capped = 0;
    /// The vertex (of M1 for residual, of M2 for targetResidual, in input order) at maxUnit.
    std::size_t maxVertex = 0;
};

/// MatchResult::targetResidual is measured on a narrow band of phi(M1)'s distance of this half
/// width, in cells of the finest level; the vertices of M2 near its edge or beyond get their
/// exact distance to every element of phi(M1), ...
constexpr double TARGET_RESIDUAL_BAND_CELLS = 4;
/// ... unless that takes more than this many point-element distances (about a second): then
/// they count at the band's half width (MatchResidual::capped; farShare stays exact, sigma being
/// 2 cells).
constexpr double TARGET_RESIDUAL_EXACT_BUDGET = 2e8;

/// One path through the levels (MatchOptions::secondPath).
struct PathSummary
{
    double coarseVolumeFactor = 1; ///< MultiscaleOptions::coarseVolumeFactor of the path
    double energy = 0;             ///< at the end of its finest level
    double farShare = 0;           ///< MatchResidual::farShare of its result
    double targetFarShare = 0;     ///< ... of its targetResidual
    /// Its levels, when it is not the kept path (MatchResult::levels holds the kept one's).
    std::vector<LevelSummary> levels;
};

/// What MatchOptions::secondPath did.
struct SecondPathSummary
{
    bool requested = false;    ///< secondPath was set
    bool ran = false;          ///< the first path left part of M1 behind and another path ran
    std::string reason;        ///< why none ran, when requested && !ran
    double farShare = 0;       ///< of the first path (MatchResidual::farShare)
    double targetFarShare = 0; ///< of the first path's targetResidual
    bool target = false;       ///< MatchOptions::secondPathTarget: targetFarShare counts too
    double threshold = 0;      ///< MatchOptions::secondPathShare
    /// Every path run, the first one first (filled when another one ran).
    std::vector<PathSummary> paths;
    std::size_t kept = 0; ///< index in paths of the result: the lowest energy
    bool done = false;    ///< the last path ended (every energy and kept are set)
    double seconds = 0;   ///< of the paths after the first
};

template <int D> struct MatchResult
{
    UnitBoxPlacement placement;
    /// Lattice of the last level run and the displacement phi - Id on its nodes (Omega units).
    std::shared_ptr<const SimplexLattice<D>> lattice;
    NodeVectors<D> displacement;
    std::vector<LevelSummary> levels;
    /// The source surface moved by phi, world space (same elements as the source).
    Surface<D> deformedSource;
    MatchResidual residual;
    /// The mirror of residual: how far the vertices of M2 are from phi(M1), the part of the
    /// target the deformed source does not reach (an addition to the paper's tab:inverseError,
    /// which measures |d2(phi(v))| only; docs/numerics.md "Target residual").
    MatchResidual targetResidual;
    LandmarkResidual landmarks;
    AutoLandmarkSummary autoLandmarks;
    InnerDistanceSummary innerDistance;
    SecondPathSummary secondPath;
    /// surfaceNoise() of the placed source and target (Omega units). Zeros when
    /// MatchOptions::hessianNoiseFactor is 0.
    std::array<double, 2> shapeNoise{{0.0, 0.0}};
    /// latticeSurfaceNoise() of the placed source and target at LATTICE_NOISE_LEVEL (Omega
    /// units). Zeros when MatchOptions::hessianNoiseFactor or hessianLatticeNoiseFactor is 0.
    std::array<double, 2> latticeNoise{{0.0, 0.0}};
    /// Each shape's Hessian smoothing length (ShapeFieldOptions::hessianSmoothingLength, Omega
    /// units): the larger of hessianNoiseFactor * shapeNoise and hessianLatticeNoiseFactor *
    /// latticeNoise.
    std::array<double, 2> smoothingLength{{0.0, 0.0}};
    double minJacobian = 0; ///< min det D phi over the simplices of the last lattice
    double totalSeconds = 0;

    bool isInterrupted() const
    {
        return !levels.empty() && levels.back().report.status == solver::Status::Interrupted;
    }
    /// True if no level was interrupted and the last one ran.
    bool isComplete() const;
};

/// Progress of match(), on the calling thread. Signatures:
/// iteration(const solver::IterationInfo&), levelStart(const LevelSummary&) (lattice and times
/// filled, report empty), levelEnd(const LevelSummary&).
struct MatchObserver
{
    solver::IterationObserver iteration;
    std::function<void(const LevelSummary&)> levelStart;
    std::function<void(const LevelSummary&)> levelEnd;
    /// After the automatic landmarks were looked for, before the first level (when requested).
    std::function<void(const AutoLandmarkSummary&)> autoLandmarks;
    /// After the inner-distance fields were computed, or the term found not to act, before the
    /// first level (when innerDistanceWeight > 0; mean and beyond are not set yet).
    std::function<void(const InnerDistanceSummary&)> innerDistance;
    /// Before each path after the first starts (MatchOptions::secondPath; paths holds those run
    /// so far, done is false), and once more when the last one ended (done, kept set).
    std::function<void(const SecondPathSummary&)> secondPath;
};

/// Matches @a source (M1) onto @a target (M2).
/// @param source, target  closed surfaces (3D: triangles) or curves (2D: segments), world space
/// @param placement       world -> Omega map (placeInUnitBox of both shapes)
/// @param opts            see MatchOptions
/// @param observer        progress callbacks, may be empty
/// @param interrupter     checked between stages and in the descent; when it fires, the result
///                        holds the last accepted iterate of the level that was running
///                        (isInterrupted()), or no lattice if no level had started
/// @throw openvdb::ValueError for invalid options or shapes (checkSurface), if a placed
///        shape leaves [0,1]^d
/// @throw InitialDeformationFolds if opts.initial sampled on the first lattice folds
///        (det D phi <= 0 on a simplex)
template <int D>
MatchResult<D> match(const Surface<D>& source, const Surface<D>& target,
                     const UnitBoxPlacement& placement, const MatchOptions& opts,
                     const MatchObserver& observer = {},
                     openvdb::util::NullInterrupter* interrupter = nullptr);

/// Summary of a lattice (counts, and the dense lattice of the same level).
template <int D> LatticeSummary summarize(const SimplexLattice<D>& lattice);

/// min det D phi of phi = Id + u over the simplices of a lattice (+inf for no simplex).
template <int D> Real minDeterminant(const SimplexLattice<D>& lattice, const NodeVectors<D>& u);

/// The Lipschitz constant of phi = Id + u on a lattice: the largest spectral norm of D phi over
/// the simplices (at least 1).
template <int D> Real lipschitzBound(const SimplexLattice<D>& lattice, const NodeVectors<D>& u);

extern template MatchResult<2> match<2>(const Surface<2>&, const Surface<2>&,
                                        const UnitBoxPlacement&, const MatchOptions&,
                                        const MatchObserver&, openvdb::util::NullInterrupter*);
extern template MatchResult<3> match<3>(const Surface<3>&, const Surface<3>&,
                                        const UnitBoxPlacement&, const MatchOptions&,
                                        const MatchObserver&, openvdb::util::NullInterrupter*);

} // namespace vdbmatch
