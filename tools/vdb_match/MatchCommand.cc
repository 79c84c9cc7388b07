/// @file MatchCommand.cc
/// @brief `vdb_match [match] SOURCE TARGET -o OUTDIR`: read two shapes, run match() with progress
///        on stderr, write deformation.vdb, deformed.vdb, deformed.obj and report.json
///        (docs/cli.md).
#include "Cli.h"
#include "CliSupport.h"
#include "ConfigFile.h"

#include <vdbmatch/Match.h>
#include <vdbmatch/eval/Consistency.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/geometry/SurfaceExtraction.h>
#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/io/InitialDeformation.h>
#include <vdbmatch/io/InverseGrid.h>
#include <vdbmatch/io/JacobianGrid.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/io/PointTable.h>
#include <vdbmatch/io/ShapeIO.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>
#include <utility>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

/// --warm-start without --warm-start-level starts at this level (sigma = 1/32 of the box), kept
/// within the requested levels and below the last one if there are two: measured on a sequence
/// at 4..7 and 4..8 (docs/batch.md), the finest level alone keeps the start's tangential errors
/// and coarser starts redo what the other pair's map already has.
constexpr int DEFAULT_WARM_START_LEVEL = 6;
/// match warns when more than this share of M2 is farther than sigma from phi(M1)
/// (MatchResult::targetResidual): the share at which the second path counts a shape as left
/// behind.
constexpr double TARGET_RESIDUAL_WARNING_SHARE = DEFAULT_SECOND_PATH_SHARE;

/// Options of `match`. Energy parameters and levels left unset take the defaults of the
/// inputs' dimension (tab:parameters).
struct MatchCliOptions
{
    std::string source, target, outDir;
    std::string grid, sourceGrid, targetGrid;
    std::optional<int> minLevel, maxLevel;
    std::optional<double> cMatch, cMem, cBend, cVol, q, theta;
    std::optional<double> coarseMembraneFactor; ///< default per preset (MatchOptions)
    std::optional<double> coarseVolumeFactor;
    std::optional<double> coarseSigmaFactor;
    std::optional<double> membraneSaturation; ///< default per preset (MatchOptions)
    std::optional<int> membraneSaturationLevels;
    double tau = EnergyParameters().tau;
    std::string preset = "default"; ///< --preset: "default" or "paper" (MatchOptions::paper)
    EnergyKind kind = EnergyKind::Symmetric;
    double margin = DEFAULT_UNIT_BOX_MARGIN;
    int hessianSmoothing = 0;
    std::optional<double> noiseSmoothing;        ///< --noise-smoothing (default per preset)
    std::optional<double> latticeNoiseSmoothing; ///< --lattice-noise-smoothing (per preset)
    std::optional<double> noiseBending;          ///< --noise-bending (default per preset)
    double refinementMargin = DEFAULT_REFINEMENT_MARGIN_CELLS;
    int maxIterations = MatchOptions::defaults(3).multiscale.descent.maxIterations;
    double energyTolerance = MatchOptions::defaults(3).multiscale.descent.energyTolerance;
    double settleTolerance = MatchOptions::defaults(3).multiscale.descent.settleTolerance;
    double toleranceCoarsening = MatchOptions::defaults(3).multiscale.toleranceCoarsening;
    double iterationCoarsening = MatchOptions::defaults(3).multiscale.iterationCoarsening;
    std::optional<double> surfaceTolerance; ///< default per dimension (MatchOptions::defaults)
    int surfaceLevels = MatchOptions::defaults(3).multiscale.surfaceLevels;
    int surfaceFromLevel = MatchOptions::defaults(3).multiscale.surfaceFromLevel;
    double gradientTolerance =
        MatchOptions::defaults(3).multiscale.descent.relativeGradientTolerance;
    std::optional<double> metricTau; ///< default per dimension and preset (MatchOptions)
    double metricTolerance = MatchOptions::defaults(3).multiscale.metric.cgTolerance;
    solver::DescentMethod method = MatchOptions::defaults(3).multiscale.descent.method;
    bool initialStepFromSlope = MatchOptions::defaults(3).multiscale.descent.initialStepFromSlope;
    double trialGrowth = MatchOptions::defaults(3).multiscale.descent.lineSearch.grow;
    int deformationLevel = 0;
    std::string config;    ///< --config FILE (applied before the other options)
    std::string init;      ///< --init DEFORMATION.vdb: start from an earlier result
    std::string warmStart; ///< --warm-start DEFORMATION.vdb: start from another pair's map
    std::optional<int> warmStartLevel;      ///< --warm-start-level L: its first level
    std::vector<std::string> landmarkFiles; ///< --landmarks A B: source and target points
    double landmarkWeight = DEFAULT_LANDMARK_WEIGHT;
    std::optional<bool> autoLandmarks; ///< --auto-landmarks on|off (default per preset)
    int autoLandmarkLevels = MatchOptions::defaults(3).autoLandmarkLevels;
    double autoLandmarkMinMotion = MatchOptions::defaults(3).autoLandmarkMinMotion;
    std::optional<bool> autoAnchors;     ///< --auto-anchors on|off (default per preset)
    std::optional<bool> landmarkAnchors; ///< --landmark-anchors on|off (default per preset)
    std::optional<bool> secondPath;      ///< --second-path on|off (default per preset)
    double secondPathShare = DEFAULT_SECOND_PATH_SHARE;
    bool secondPathTarget = false;              ///< --second-path-target on|off
    std::optional<double> anchorWeight;         ///< --anchor-weight (default per dimension)
    std::optional<std::size_t> anchorCount;     ///< --anchor-count (default per dimension)
    StillAnchorOptions anchorOptions;           ///< --anchor-radius, --anchor-tolerance
    std::optional<double> anchorNoiseTolerance; ///< --anchor-noise-tolerance (per preset)
    std::optional<double> innerDistanceWeight;  ///< --inner-distance-weight (default per dimension)
    std::optional<double> rigidLimbWeight;      ///< --rigid-limb-weight (default per dimension)
    double rigidLimbMinMotion = MatchOptions().rigidLimbMinMotion; ///< --rigid-limb-min-motion
    std::optional<double> rigidLimbAnchorRadius; ///< --rigid-limb-anchor-radius (per dimension)
    RigidLimbOptions rigidLimbOptions;           ///< --rigid-limb-count, --rigid-limb-reach
    bool rigidSegmentGiven = false; ///< --rigid-segment given (else the default per dimension)
    double innerDistanceTolerance = DEFAULT_INNER_DISTANCE_TOLERANCE;
    double innerDistanceRatio = DEFAULT_INNER_DISTANCE_RATIO;
    int innerDistanceLevel = 0;     ///< --inner-distance-level (0: per dimension)
    int innerDistanceLevels = 0;    ///< --inner-distance-levels (0: every level)
    std::optional<double> isoValue; ///< --iso-value: densities converted at this value
    bool writeInverse = true;       ///< inverse.vdb
    bool writeJacobian = true;      ///< jacobian.vdb
    bool logJacobian = false;       ///< jacobian.vdb holds log det
    bool half = false;              ///< half-float storage of the vector grids
    int progressEvery = 10;
    int threads = 0;
    bool quiet = false;
    bool strict = false;
    std::string commandLine;
};

/// One line on what the automatic landmarks did; @a tolerance is the anchors' fixed one
/// (--anchor-tolerance), named when the noise raised it.
std::string
autoLandmarkLine(const AutoLandmarkSummary& a, int firstLevel, double tolerance)
{
    const std::string anchors =
        a.anchors.empty()
            ? (a.anchorReason.empty() ? std::string() : "; no anchors: " + a.anchorReason)
            : ", with " + std::to_string(a.anchors.size()) +
                  " still anchors at every level (M1 and M2 coincide on " +
                  fixed("%.0f", 100 * a.anchorCoincidentShare) + "% of their vertices" +
                  (a.anchorTolerance > tolerance
                       ? ", within " + fixed("%.2e", a.anchorTolerance) +
                             " of the unit box: the tolerance follows the noise"
                       : std::string()) +
                  ")";
    std::string limbs;
    for (const RigidLimbFit& l : a.limbs) {
        limbs += std::string(l.segment ? "; segment of limb " : "; limb ") +
                 std::to_string(l.extremity + 1) +
                 (l.used ? ": rigid, turned " + fixed("%.0f", l.angle) + " deg (fit " +
                               fixed("%.2e", l.residual) + ")"
                         : ": not held: " + l.reason);
    }
    if (!a.limbSource.empty())
        limbs += ", " + std::to_string(a.limbSource.size()) +
                 " limb points at every level (anchors' radius " + fixed("%.3g", a.anchorRadius) +
                 ")";
    const std::string rest = anchors + limbs;
    if (!a.used) return "automatic landmarks: not used: " + a.reason + rest;
    return "automatic landmarks: " + std::to_string(a.source.size()) +
           " extremities paired (distortion " + fixed("%.3f", a.distortion) + ", largest motion " +
           fixed("%.3g", a.maxMotion) + " > " + fixed("%.3g", a.minMotion) +
           " of the unit box), acting at levels " + std::to_string(firstLevel) + ".." +
           std::to_string(a.lastLevel) + rest;
}

/// One line on the inner-distance term before the first level: its fields, or why it does not
/// act.
std::string
innerDistanceStartLine(const InnerDistanceSummary& f)
{
    if (!f.used) return "inner distance: not used: " + f.reason;
    return "inner distance: F from each paired extremity on the lattice of level " +
           std::to_string(f.level) + " (" + fixed("%.1f", f.seconds) + " s), over " +
           std::to_string(f.points) + " vertices of M1" +
           (f.ratio > 1 ? " (" + fixed("%.0f", 100 * f.share) +
                              "% of it: those whose second-nearest extremity is at least " +
                              fixed("%.3g", f.ratio) + "x as far as their nearest)"
                        : std::string()) +
           ", weight " + fixed("%.4g", f.weight) + ", tolerance " + fixed("%.3g", f.tolerance);
}

/// One line on what the inner-distance term did.
std::string
innerDistanceLine(const InnerDistanceSummary& f)
{
    if (!f.used) return "inner distance: not used: " + f.reason;
    return "inner distance: |F2_k(phi(x)) - F1_k(x)| over M1 " + fixed("%.3g", f.mean) + " (" +
           fixed("%.3g", f.startMean) + " at phi = Id) of the unit box, " +
           fixed("%.0f", 100 * f.beyond) + "% of M1 beyond the tolerance " +
           fixed("%.3g", f.tolerance) + " (" + fixed("%.0f", 100 * f.startBeyond) +
           "% at phi = Id)";
}

/// Where a residual is largest: the world position of its vertex in @a shape (the input's
/// points: the mesh, polyline or the zero level set's mesh), 2 or 3 coordinates.
Json
vertexWorld(const Shape& shape, std::size_t v)
{
    Json p = Json::array();
    if (shape.dim == 2) {
        if (v < shape.curve.points.size())
            for (int a = 0; a < 2; ++a)
                p.push_back(shape.curve.points[v][a]);
    } else if (v < shape.surface.points.size()) {
        for (int a = 0; a < 3; ++a)
            p.push_back(shape.surface.points[v][a]);
    }
    return p;
}

/// report.json's result.residual (over @a shape = M1) and result.targetResidual (M2).
Json
residualJson(const MatchResidual& r, const Shape& shape)
{
    return Json{{"meanWorld", r.meanWorld},
                {"maxWorld", r.maxWorld},
                {"meanUnit", r.meanUnit},
                {"maxUnit", r.maxUnit},
                {"samples", r.samples},
                {"farShare", r.farShare},
                {"capped", r.capped},
                {"maxVertex", r.maxVertex},
                {"maxAtWorld", vertexWorld(shape, r.maxVertex)}};
}

/// The line on the target residual (MatchResult::targetResidual over @a target, M2) after the
/// summary.
std::string
targetResidualLine(const MatchResidual& r, const Shape& target)
{
    std::string at;
    for (const Json& x : vertexWorld(target, r.maxVertex))
        at += (at.empty() ? "(" : ", ") + fixed("%.4g", x.get<double>());
    std::string line = "target residual (distance of M2's vertices to phi(M1)): mean " +
                       fixed("%.3e", r.meanWorld) + " max " + fixed("%.3e", r.maxWorld) +
                       (at.empty() ? std::string() : " at " + at + ")") + " (world units; " +
                       fixed("%.2e", r.meanUnit) + " of the unit box), " +
                       fixed("%.1f", 100 * r.farShare) + "% of M2 farther than sigma";
    if (r.capped) {
        line += " (" + std::to_string(r.capped) + " vertices beyond " +
                formatNumber(TARGET_RESIDUAL_BAND_CELLS) + " cells counted at " +
                formatNumber(TARGET_RESIDUAL_BAND_CELLS) + ": mean and max are lower bounds)";
    }
    return line;
}

/// One line on the noise-adaptive Hessian smoothing (MatchOptions::hessianNoiseFactor): each
/// shape's noise and the levels at which its Hessian is smoothed, and the bending weight's
/// factor at the finest level (MatchOptions::noiseBendingPasses) when it is below 1.
template <int D>
std::string
noiseLine(const MatchResult<D>& r, const MatchOptions& opts)
{
    std::string line = "noise smoothing:";
    const char* names[2] = {"source", "target"};
    for (int s = 0; s < 2; ++s) {
        line += std::string(s ? ";" : "") + " " + names[s] + " noise " +
                fixed("%.2e", r.shapeNoise[s]) + " of the unit box";
        if (opts.hessianLatticeNoiseFactor > 0)
            line += " (lattice " + fixed("%.2e", r.latticeNoise[s]) + ")";
        const double length = r.smoothingLength[s];
        int from = 0;
        for (int l = opts.multiscale.maxLevel; l >= opts.multiscale.minLevel; --l)
            if (lengthSmoothingPasses(length, std::ldexp(1.0, -l)) > 0) from = l;
        if (from == 0) {
            line += ", no level smoothed";
        } else {
            const int last =
                lengthSmoothingPasses(length, std::ldexp(1.0, -opts.multiscale.maxLevel));
            line += ", Hessian smoothed over " + fixed("%.2e", length) + " from level " +
                    std::to_string(from) + " (" + std::to_string(last) +
                    (last == 1 ? " pass" : " passes") + " at level " +
                    std::to_string(opts.multiscale.maxLevel) + ")";
        }
    }
    const double factor = r.levels.empty() ? 1.0 : r.levels.back().bendingFactor;
    if (factor < 1.0)
        line += "; c_bend x" + fixed("%.3g", factor) + " at level " +
                std::to_string(r.levels.back().level);
    return line;
}

/// One line on what the second path did (MatchOptions::secondPath), before each further path
/// and when the last one ended.
std::string
secondPathLine(const SecondPathSummary& sp)
{
    std::string line =
        "second path: " + fixed("%.1f", 100 * sp.farShare) +
        "% of M1 ended farther than sigma from M2" +
        (sp.target ? " and " + fixed("%.1f", 100 * sp.targetFarShare) + "% of M2 from phi(M1)"
                   : std::string()) +
        " on the first path";
    if (sp.done) {
        line += "; energies";
        for (std::size_t k = 0; k < sp.paths.size(); ++k) {
            const PathSummary& p = sp.paths[k];
            line += std::string(k ? "," : "") + " " + fixed("%.4g", p.energy) + " (c_vol x" +
                    formatNumber(p.coarseVolumeFactor) + " below the finest level, " +
                    fixed("%.1f", 100 * p.farShare) + "% far" +
                    (sp.target ? ", " + fixed("%.1f", 100 * p.targetFarShare) + "% of M2"
                               : std::string()) +
                    ")";
        }
        return line + ": kept path " + std::to_string(sp.kept + 1) + " of " +
               std::to_string(sp.paths.size());
    }
    const PathSummary& last = sp.paths.back();
    return line +
           (sp.paths.size() > 1
                ? " and on path " + std::to_string(sp.paths.size()) + " (" +
                      fixed("%.1f", 100 * last.farShare) + "%" +
                      (sp.target ? ", " + fixed("%.1f", 100 * last.targetFarShare) + "% of M2"
                                 : std::string()) +
                      ")"
                : std::string()) +
           " (energy " + fixed("%.4g", last.energy) +
           "): running the levels again with the volume weight x" +
           formatNumber(last.coarseVolumeFactor * SECOND_PATH_VOLUME_FACTOR) +
           " below the finest level";
}

std::vector<Option<MatchCliOptions>>
matchOptionTable()
{
    const EnergyParameters p3 = EnergyParameters::defaults(3), p2 = EnergyParameters::defaults(2);
    const MatchCliOptions d;
    auto both = [](double a3, double a2) {
        return formatNumber(a3) + " in 3D, " + formatNumber(a2) + " in 2D";
    };
    using O = MatchCliOptions;
    // clang-format off
    return {
        {"--output,-o", "OUTDIR", "Input and output",
         "output directory, created if missing; existing outputs are replaced (required)",
         [](O& o, const std::string& v) { o.outDir = v; }},
        {"--source", "FILE", "Input and output",
         "the source shape M1, instead of the first positional argument",
         [](O& o, const std::string& v) { o.source = v; }},
        {"--target", "FILE", "Input and output",
         "the target shape M2, instead of the second positional argument",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--grid", "NAME", "Input and output",
         "grid to read from .vdb inputs (default: the only float grid of each file)",
         [](O& o, const std::string& v) { o.grid = v; }},
        {"--source-grid", "NAME", "Input and output", "grid to read from SOURCE (not with --grid)",
         [](O& o, const std::string& v) { o.sourceGrid = v; }},
        {"--target-grid", "NAME", "Input and output", "grid to read from TARGET (not with --grid)",
         [](O& o, const std::string& v) { o.targetGrid = v; }},
        {"--iso-value", "X", "Input and output",
         "read .vdb fog volumes (densities) as the level set of their iso-surface at density X, "
         "inside where the density exceeds X (default: densities are refused)",
         [](O& o, const std::string& v) { o.isoValue = parseDouble("--iso-value", v); }},
        {"--deformation-level", "L", "Input and output",
         "node spacing 2^-L of deformation.vdb in the unit box (default: the finest level, "
         "which reproduces phi exactly)",
         [](O& o, const std::string& v) { o.deformationLevel = parseInt("--deformation-level", v); }},
        {"--config", "FILE", "Input and output",
         "parameters from a JSON file: a report.json (its \"parameters\") or an object with those "
         "keys; options on the command line override it",
         [](O& o, const std::string& v) { o.config = v; }},
        {"--init", "DEFORMATION.vdb", "Input and output",
         "start from an earlier result of the same SOURCE and TARGET (its deformation.vdb): the "
         "run starts at the first level finer than that result's finest (the same level if it "
         "was interrupted; the last requested level if it is already as fine)",
         [](O& o, const std::string& v) { o.init = v; }},
        {"--warm-start", "DEFORMATION.vdb", "Input and output",
         "start from the map of another pair (its deformation.vdb), e.g. frames k-1 -> k of a "
         "sequence for k -> k+1: carried through world space into this pair's placement, it is "
         "phi at the start of --warm-start-level (docs/batch.md says when it helps); a start that "
         "folds there falls back to the identity",
         [](O& o, const std::string& v) { o.warmStart = v; }},
        {"--warm-start-level", "L", "Input and output",
         "the level whose descent starts from --warm-start; the levels before it are skipped "
         "(cells stay no coarser than the first of --levels) (default: " +
             std::to_string(DEFAULT_WARM_START_LEVEL) + ", within the levels and below the last)",
         [](O& o, const std::string& v) { o.warmStartLevel = parseInt("--warm-start-level", v); }},
        {"--no-inverse", nullptr, "Input and output",
         "do not write inverse.vdb (the exact inverse phi^-1 at every node)",
         [](O& o, const std::string&) { o.writeInverse = false; }},
        {"--no-jacobian", nullptr, "Input and output",
         "do not write jacobian.vdb (det D phi per voxel cell)",
         [](O& o, const std::string&) { o.writeJacobian = false; }},
        {"--log-jacobian", nullptr, "Input and output",
         "jacobian.vdb holds log det D phi (grid log_det_jacobian)",
         [](O& o, const std::string&) { o.logJacobian = true; }},
        {"--half", nullptr, "Input and output",
         "store deformation.vdb and inverse.vdb in half precision (about half the size; "
         "displacements rounded to 11 significant bits, docs/apply.md)",
         [](O& o, const std::string&) { o.half = true; }},
        {"--min-level", "L", "Levels and domain",
         "first (coarsest) level, h = 2^-L (default 4)"
             "\npaper: l_min, tab:parameters",
         [](O& o, const std::string& v) { o.minLevel = parseInt("--min-level", v); }},
        {"--max-level", "L", "Levels and domain",
         "last (finest) level (default 8 in 3D, 9 in 2D)"
             "\npaper: l_max, tab:parameters",
         [](O& o, const std::string& v) { o.maxLevel = parseInt("--max-level", v); }},
        {"--levels", "A..B", "Levels and domain", "both at once, e.g. 4..7",
         [](O& o, const std::string& v) {
             const size_t dots = v.find("..");
             if (dots == std::string::npos) throw UsageError("--levels expects A..B, got '" + v + "'");
             o.minLevel = parseInt("--levels", v.substr(0, dots));
             o.maxLevel = parseInt("--levels", v.substr(dots + 2));
         }},
        {"--margin", "X", "Levels and domain",
         "space left on each side of the shapes' common bounding box in the unit box, [0, 0.5) "
         "(default " + formatNumber(d.margin) + ")",
         [](O& o, const std::string& v) { o.margin = parseDouble("--margin", v); }},
        {"--refine-margin", "CELLS", "Levels and domain",
         "extra width of the finest cells around the bands, in cells (default " +
             formatNumber(d.refinementMargin) + ")",
         [](O& o, const std::string& v) { o.refinementMargin = parseDouble("--refine-margin", v); }},
        {"--preset", "NAME", "Energy (paper tab:parameters)",
         "'default' or 'paper': the paper's experiment, tab:parameters and its levels with none of "
         "our additions that change the result (no surface test, one c_mem at every level, no "
         "automatic landmarks or anchors, no second path, no landmarks unless given); "
         "options given override it (default: default)",
         [](O& o, const std::string& v) {
             if (v != "default" && v != "paper")
                 throw UsageError("--preset expects 'default' or 'paper', got '" + v + "'");
             o.preset = v;
         }},
        {"--energy", "KIND", "Energy (paper tab:parameters)",
         "symmetric (eq:Esym) or directional (eq:Ecomparison) (default symmetric)",
         [](O& o, const std::string& v) {
             if (v != "symmetric" && v != "directional") {
                 throw UsageError("--energy expects 'symmetric' or 'directional', got '" + v + "'");
             }
             o.kind = parseEnergyKind(v);
         }},
        {"--c-match", "X", "Energy (paper tab:parameters)",
         "weight of the matching term (default " + both(p3.cMatch, p2.cMatch) + ")" +
             "\npaper: c_match, eq:EsymMatch",
         [](O& o, const std::string& v) { o.cMatch = parseDouble("--c-match", v); }},
        {"--c-mem", "X", "Energy (paper tab:parameters)",
         "weight of the membrane term (default " + both(p3.cMem, p2.cMem) + ")" +
             "\npaper: c_mem, eq:EsymMem",
         [](O& o, const std::string& v) { o.cMem = parseDouble("--c-mem", v); }},
        {"--coarse-membrane-factor", "F", "Energy (paper tab:parameters)",
         "an addition to the paper: the levels below the finest weigh the membrane term by F "
         "c_mem, the finest level by c_mem (default " +
             formatNumber(DEFAULT_MATCH_COARSE_MEMBRANE_FACTOR) +
             "; --preset paper: 1, the paper's single c_mem)",
         [](O& o, const std::string& v) {
             o.coarseMembraneFactor = parseDouble("--coarse-membrane-factor", v);
         }},
        {"--membrane-saturation", "X", "Energy (paper tab:parameters)",
         "an addition to the paper: at the first --membrane-saturation-levels levels, take both "
         "membrane densities through s log(1 + W/s), so that a joint's stretch stays at the "
         "joint; >= 0, 0: the paper's W (default " +
             formatNumber(DEFAULT_MATCH_MEMBRANE_SATURATION_3D) + " in 3D, " +
             formatNumber(DEFAULT_MATCH_MEMBRANE_SATURATION_2D) + " in 2D; --preset paper: 0)",
         [](O& o, const std::string& v) {
             o.membraneSaturation = parseDouble("--membrane-saturation", v);
         }},
        {"--membrane-saturation-levels", "N", "Energy (paper tab:parameters)",
         "levels, from the first, at which --membrane-saturation acts, >= 0 (default " +
             std::to_string(DEFAULT_MATCH_MEMBRANE_SATURATION_LEVELS) + ")",
         [](O& o, const std::string& v) {
             o.membraneSaturationLevels = parseInt("--membrane-saturation-levels", v);
         }},
        {"--c-bend", "X", "Energy (paper tab:parameters)",
         "weight of the bending term (default " + both(p3.cBend, p2.cBend) + ")" +
             "\npaper: c_bend, eq:EsymBend",
         [](O& o, const std::string& v) { o.cBend = parseDouble("--c-bend", v); }},
        {"--c-vol", "X", "Energy (paper tab:parameters)",
         "weight of the volume term, times sigma^theta (default " + both(p3.cVol, p2.cVol) + ")" +
             "\npaper: c_vol, eq:EsymVol",
         [](O& o, const std::string& v) { o.cVol = parseDouble("--c-vol", v); }},
        {"--coarse-volume-factor", "F", "Energy (paper tab:parameters)",
         "an addition to the paper: the levels below the finest weigh the volume term by F c_vol, "
         "the finest level by c_vol (default 1)",
         [](O& o, const std::string& v) {
             o.coarseVolumeFactor = parseDouble("--coarse-volume-factor", v);
         }},
        {"--coarse-sigma-factor", "F", "Energy (paper tab:parameters)",
         "an addition to the paper: the levels below the finest use the band width sigma = 2 F h, "
         "the finest level sigma = 2h; in [" +
             formatNumber(multiscale::MultiscaleOptions::MIN_COARSE_SIGMA_FACTOR) + ", " +
             formatNumber(multiscale::MultiscaleOptions::MAX_COARSE_SIGMA_FACTOR) + "] (default " +
             formatNumber(multiscale::MultiscaleOptions().coarseSigmaFactor) + ")",
         [](O& o, const std::string& v) {
             o.coarseSigmaFactor = parseDouble("--coarse-sigma-factor", v);
         }},
        {"--q", "X", "Energy (paper tab:parameters)",
         "matching exponent, weight sigma^-q (default " + both(p3.q, p2.q) + ")" +
             "\npaper: q, eq:EsymMatch",
         [](O& o, const std::string& v) { o.q = parseDouble("--q", v); }},
        {"--theta", "X", "Energy (paper tab:parameters)",
         "volume exponent, weight sigma^theta (default " + both(p3.theta, p2.theta) + ")" +
             "\npaper: theta, eq:EsymVol",
         [](O& o, const std::string& v) { o.theta = parseDouble("--theta", v); }},
        {"--tau", "X", "Energy (paper tab:parameters)",
         "eigenvalue floor of the regularized shape operator, 1/unit-box length, > 0 (default " +
             formatNumber(d.tau) + ")" +
             "\npaper: tau, eq:defSi",
         [](O& o, const std::string& v) { o.tau = parseDouble("--tau", v); }},
        {"--hessian-smoothing", "N", "Energy (paper tab:parameters)",
         "[1,2,1]/4 smoothing passes of the distance Hessian at every level, >= 0 (default 0: "
         "the paper's Hessian). Against a scanner's noise on the inputs (docs/numerics.md)",
         [](O& o, const std::string& v) { o.hessianSmoothing = parseInt("--hessian-smoothing", v); }},
        {"--noise-smoothing", "F", "Energy (paper tab:parameters)",
         "an addition to the paper: smooth each shape's distance Hessian over F times the shape's "
         "own vertex noise (median normal part of the umbrella vector's change), the same length "
         "at every level, so only the fine levels of a noisy shape (a scan) are smoothed and a "
         "noise-free one is untouched; >= 0, 0: off (default " +
             formatNumber(NOISE_SMOOTHING_LENGTH_FACTOR) +
             "; --preset paper: 0). report.json \"noise\" gives each shape's noise and length "
             "(docs/numerics.md)",
         [](O& o, const std::string& v) { o.noiseSmoothing = parseDouble("--noise-smoothing", v); }},
        {"--lattice-noise-smoothing", "G", "Energy (paper tab:parameters)",
         "an addition to the paper: with --noise-smoothing, smooth each shape's Hessian over at "
         "least G times the noise a lattice of h = 1/128 sees on it (median change of the "
         "distance Hessian under one smoothing pass, times h^2), which reads noise correlated "
         "over a few vertices at its amplitude where the vertex noise reads it low; >= 0, 0: off "
         "(default " +
             formatNumber(LATTICE_NOISE_SMOOTHING_FACTOR_3D) +
             " in 3D, 0 in 2D; --preset paper: 0). report.json \"noise\" gives each shape's reading "
             "(docs/numerics.md \"Correlated noise\")",
         [](O& o, const std::string& v) {
             o.latticeNoiseSmoothing = parseDouble("--lattice-noise-smoothing", v);
         }},
        {"--noise-bending", "X", "Energy (paper tab:parameters)",
         "an addition to the paper: at a level where --noise-smoothing gives a shape's Hessian n "
         "passes (the larger n of the two shapes), weigh the bending term by c_bend / (1 + n/X): a "
         "smoothed Hessian is a less certain shape operator. Noise-free shapes get no pass and "
         "the paper's weight; >= 0, 0: off (default " +
             formatNumber(DEFAULT_NOISE_BENDING_PASSES) +
             "; --preset paper: 0). report.json \"levels\" give each level's \"bendingFactor\" "
             "(docs/numerics.md)",
         [](O& o, const std::string& v) { o.noiseBending = parseDouble("--noise-bending", v); }},
        {"--landmarks", "A.csv B.csv", "Landmarks (an addition to the paper)",
         "corresponding points: row k of A (on the source) should map to row k of B (on the "
         "target); .csv/.xyz/.txt tables with columns x, y (and z in 3D), world units of the "
         "inputs. Adds the soft term c_lm/K sum |phi(a_k) - b_k|^2 (docs/numerics.md)",
         [](O& o, const std::string& v) { o.landmarkFiles.push_back(v); }},
        {"--landmark-weight", "X", "Landmarks (an addition to the paper)",
         "c_lm, the weight of the landmark term (its distances in unit-box lengths) (default " + formatNumber(d.landmarkWeight) + ")",
         [](O& o, const std::string& v) { o.landmarkWeight = parseDouble("--landmark-weight", v); }},
        {"--auto-landmarks", "on|off", "Landmarks (an addition to the paper)",
         "without --landmarks: find the extremities of both shapes (limb tips, head, tail), pair "
         "them by their inner distances and use them as landmarks at the first "
         "--auto-landmark-levels levels (docs/numerics.md) (default " +
             std::string(MatchOptions::defaults(3).autoLandmarks ? "on" : "off") +
             "; --preset paper: off)",
         [](O& o, const std::string& v) { o.autoLandmarks = parseOnOff("--auto-landmarks", v); }},
        {"--auto-landmark-levels", "N", "Landmarks (an addition to the paper)",
         "levels, from the first, at which the automatic landmarks act, >= 1 (default " +
             std::to_string(d.autoLandmarkLevels) + ")",
         [](O& o, const std::string& v) {
             o.autoLandmarkLevels = parseInt("--auto-landmark-levels", v);
         }},
        {"--auto-landmark-min-motion", "X", "Landmarks (an addition to the paper)",
         "the automatic landmarks act only when some extremity moves farther than X sigma of the "
         "first level, >= 0; 0: whenever the extremities are paired (default " +
             formatNumber(d.autoLandmarkMinMotion) + ")",
         [](O& o, const std::string& v) {
             o.autoLandmarkMinMotion = parseDouble("--auto-landmark-min-motion", v);
         }},
        {"--auto-anchors", "on|off", "Landmarks (an addition to the paper)",
         "when the automatic landmarks act (or --landmarks are given, with --landmark-anchors "
         "on) and some extremity stays while another moves (at "
         "least four times as far): hold still, at every level, up to --anchor-count points of M1 "
         "and M2 around which the other shape coincides (what the articulation left in place; "
         "the same points either way round; docs/numerics.md) (default " +
             std::string(MatchOptions::defaults(3).autoAnchors ? "on" : "off") +
             "; --preset paper: off)",
         [](O& o, const std::string& v) { o.autoAnchors = parseOnOff("--auto-anchors", v); }},
        {"--landmark-anchors", "on|off", "Landmarks (an addition to the paper)",
         "with --landmarks and --auto-anchors on: find and pair the extremities anyway, not as "
         "landmarks but to tell an articulation, and then hold the automatic anchors at every "
         "level beside the given landmarks, with the inner-distance term from those extremities "
         "(off: given landmarks turn both off, as before 2026-11-29; docs/numerics.md) (default " +
             std::string(MatchOptions::defaults(3).landmarkAnchors ? "on" : "off") +
             "; --preset paper: off)",
         [](O& o, const std::string& v) {
             o.landmarkAnchors = parseOnOff("--landmark-anchors", v);
         }},
        {"--anchor-weight", "X", "Landmarks (an addition to the paper)",
         "c_an, the total weight of the automatic anchors, >= 0 (default " +
             both(DEFAULT_ANCHOR_WEIGHT_3D, DEFAULT_ANCHOR_WEIGHT_2D) + ")",
         [](O& o, const std::string& v) { o.anchorWeight = parseDouble("--anchor-weight", v); }},
        {"--anchor-count", "N", "Landmarks (an addition to the paper)",
         "most automatic anchors, farthest-point samples of where M1 and M2 coincide, >= 1 "
         "(default " + both(double(DEFAULT_ANCHOR_COUNT_3D), double(DEFAULT_ANCHOR_COUNT_2D)) +
             ")",
         [](O& o, const std::string& v) {
             const int n = parseInt("--anchor-count", v);
             if (n < 1) throw UsageError("--anchor-count must be >= 1, got " + v);
             o.anchorCount = std::size_t(n);
         }},
        {"--anchor-radius", "X", "Landmarks (an addition to the paper)",
         "M1 and M2 coincide around a vertex when every vertex of its shape within X of it is "
         "within --anchor-tolerance of the other shape; unit-box lengths (default " +
             formatNumber(d.anchorOptions.radius) + ")",
         [](O& o, const std::string& v) {
             o.anchorOptions.radius = parseDouble("--anchor-radius", v);
         }},
        {"--anchor-tolerance", "X", "Landmarks (an addition to the paper)",
         "a vertex of M1 is on M2 when |d2| <= X, one of M2 on M1 when |d1| <= X; unit-box "
         "lengths (default " +
             formatNumber(d.anchorOptions.tolerance) + ")",
         [](O& o, const std::string& v) {
             o.anchorOptions.tolerance = parseDouble("--anchor-tolerance", v);
         }},
        {"--anchor-noise-tolerance", "K", "Landmarks (an addition to the paper)",
         "the anchors' tolerance is at least K times the two shapes' correlated noise: the part "
         "of each shape's lattice noise reading (--lattice-noise-smoothing) that its vertex "
         "noise does not account for as white noise. A scan whose noise is correlated over a "
         "few vertices then still coincides with the other shape where nothing moved; white "
         "noise and noise-free shapes keep --anchor-tolerance. The nearer anchors of a held "
         "rigid limb (--rigid-limb-anchor-radius) take K times the whole lattice reading, white "
         "noise included. Needs the lattice reading; "
         ">= 0, 0: off (default " +
             formatNumber(DEFAULT_ANCHOR_NOISE_FACTOR_3D) +
             " in 3D, 0 in 2D; --preset paper: 0). report.json \"autoLandmarks\" gives the \"anchorTolerance\" "
             "used (docs/numerics.md \"The anchors' tolerance follows the noise\")",
         [](O& o, const std::string& v) {
             o.anchorNoiseTolerance = parseDouble("--anchor-noise-tolerance", v);
         }},
        {"--rigid-limb-weight", "X", "Landmarks (an addition to the paper)",
         "c_rl, the total weight of the rigid limbs' points, >= 0: when the automatic anchors "
         "act, each limb whose extremity moved farther than --rigid-limb-min-motion and that one "
         "rigid motion carries from M1 to M2 "
         "(fitted by closest points both ways, so that the match M2 -> M1 holds the inverse "
         "motion; without a turn about its own axis) has --rigid-limb-count "
         "points held at their images at every level, so that a round limb does not turn about "
         "its axis (docs/numerics.md \"Rigid limbs\"); 0: off (default " +
             formatNumber(DEFAULT_RIGID_LIMB_WEIGHT) + "; --preset paper: 0)",
         [](O& o, const std::string& v) {
             o.rigidLimbWeight = parseDouble("--rigid-limb-weight", v);
         }},
        {"--rigid-limb-min-motion", "K", "Landmarks (an addition to the paper)",
         "rigid limbs only when an extremity moved farther than K sigma of the first level, "
         "and then for each extremity that moved farther than that or than half the largest "
         "motion, >= 0 (default " +
             formatNumber(d.rigidLimbMinMotion) + ")",
         [](O& o, const std::string& v) {
             o.rigidLimbMinMotion = parseDouble("--rigid-limb-min-motion", v);
         }},
        {"--rigid-limb-anchor-radius", "X", "Landmarks (an addition to the paper)",
         "when a rigid limb is held, the anchors are sought again with this --anchor-radius, if "
         "smaller, so that they come nearer the joints, and with a tolerance of at least "
         "--anchor-noise-tolerance times the shapes' whole lattice noise reading, >= 0; 0: the "
         "anchors keep theirs "
         "(default " +
             both(DEFAULT_RIGID_LIMB_ANCHOR_RADIUS_3D, 0.0) + "; --preset paper: 0)",
         [](O& o, const std::string& v) {
             o.rigidLimbAnchorRadius = parseDouble("--rigid-limb-anchor-radius", v);
         }},
        {"--rigid-limb-count", "N", "Landmarks (an addition to the paper)",
         "points per rigid limb, half on each shape (an even N: the match M2 -> M1 holds the "
         "same pairs), >= 2 (default " +
             formatNumber(double(d.rigidLimbOptions.count)) + ")",
         [](O& o, const std::string& v) {
             const int n = parseInt("--rigid-limb-count", v);
             if (n < 2) throw UsageError("--rigid-limb-count must be >= 2, got " + v);
             o.rigidLimbOptions.count = std::size_t(n);
         }},
        {"--rigid-limb-reach", "X", "Landmarks (an addition to the paper)",
         "a rigid limb is the part of the surface nearer its tip than X times the tip's geodesic "
         "distance to the nearest anchor (the joint), 0 < X <= 0.8 (default " +
             formatNumber(d.rigidLimbOptions.reach) + ")",
         [](O& o, const std::string& v) {
             const double x = parseDouble("--rigid-limb-reach", v);
             if (!(x > 0 && x <= 0.8))
                 throw UsageError("--rigid-limb-reach must be in (0, 0.8], got " + v);
             o.rigidLimbOptions.reach = x;
         }},
        {"--rigid-segment", "FROM,TO|off", "Landmarks (an addition to the paper)",
         "with the rigid limbs, for an extremity that stayed (--rigid-segment-tip-motion) "
         "while its limb moved (a foot planted below a bent knee), the segment next to its "
         "joint: the vertices between FROM and TO of the way from the tip to the joint (the "
         "nearest anchor), along the straight line between them, of those nearer this tip than "
         "any other; fitted rigidly as a limb is and held the same way when it fits, turned by "
         "at least --rigid-segment-min-angle and keeps its joint (the thigh), "
         "0 <= FROM < TO <= 1 (default " +
             formatNumber(RigidLimbOptions().segmentFrom) + "," +
             formatNumber(RigidLimbOptions().segmentTo) +
             " in 2D, off in 3D; docs/numerics.md \"Rigid segments\")",
         [](O& o, const std::string& v) {
             o.rigidSegmentGiven = true;
             if (v == "off") {
                 o.rigidLimbOptions.segmentTo = 0;
                 return;
             }
             const std::size_t comma = v.find(',');
             if (comma == std::string::npos)
                 throw UsageError("--rigid-segment takes FROM,TO or off, got " + v);
             const double from = parseDouble("--rigid-segment", v.substr(0, comma)),
                          to = parseDouble("--rigid-segment", v.substr(comma + 1));
             if (!(from >= 0 && from < to && to <= 1))
                 throw UsageError("--rigid-segment needs 0 <= FROM < TO <= 1, got " + v);
             o.rigidLimbOptions.segmentFrom = from;
             o.rigidLimbOptions.segmentTo = to;
         }},
        {"--rigid-segment-min-angle", "X", "Landmarks (an addition to the paper)",
         "a rigid segment is held when turned by at least X degrees, >= 0 (default " +
             formatNumber(d.rigidLimbOptions.segmentMinAngle) + ")",
         [](O& o, const std::string& v) {
             const double x = parseDouble("--rigid-segment-min-angle", v);
             if (!(x >= 0)) throw UsageError("--rigid-segment-min-angle must be >= 0, got " + v);
             o.rigidLimbOptions.segmentMinAngle = x;
         }},
        {"--rigid-segment-tip-motion", "X", "Landmarks (an addition to the paper)",
         "a rigid segment is sought only for an extremity that moved by at most X (unit box), "
         ">= 0 (default " +
             formatNumber(d.rigidLimbOptions.segmentMaxTipMotion) + ": the tip stayed)",
         [](O& o, const std::string& v) {
             const double x = parseDouble("--rigid-segment-tip-motion", v);
             if (!(x >= 0)) throw UsageError("--rigid-segment-tip-motion must be >= 0, got " + v);
             o.rigidLimbOptions.segmentMaxTipMotion = x;
         }},
        {"--inner-distance-weight", "X", "Landmarks (an addition to the paper)",
         "c_F of the inner-distance term, >= 0: when the automatic anchors act (an "
         "articulation), keep each "
         "point's inner distance to its nearest extremity's partner, c_F times the mean over M1 "
         "of max(|F2_k(phi(x)) - F1_k(x)| - tau, 0)^2 (docs/numerics.md); 0: off (default " +
             both(DEFAULT_INNER_DISTANCE_WEIGHT_3D, DEFAULT_INNER_DISTANCE_WEIGHT_2D) +
             "; --preset paper: 0)",
         [](O& o, const std::string& v) {
             o.innerDistanceWeight = parseDouble("--inner-distance-weight", v);
         }},
        {"--inner-distance-tolerance", "X", "Landmarks (an addition to the paper)",
         "tau of the inner-distance term, unit-box lengths, >= 0 (default " +
             formatNumber(DEFAULT_INNER_DISTANCE_TOLERANCE) + ")",
         [](O& o, const std::string& v) {
             o.innerDistanceTolerance = parseDouble("--inner-distance-tolerance", v);
         }},
        {"--inner-distance-ratio", "X", "Landmarks (an addition to the paper)",
         "only the points of M1 whose second-nearest extremity is at least X times as far "
         "inside M1 as their nearest are in the inner-distance term, X >= 1; 1: every point "
         "(default " +
             formatNumber(DEFAULT_INNER_DISTANCE_RATIO) + ")",
         [](O& o, const std::string& v) {
             o.innerDistanceRatio = parseDouble("--inner-distance-ratio", v);
             if (!(o.innerDistanceRatio >= 1) || !std::isfinite(o.innerDistanceRatio))
                 throw UsageError("--inner-distance-ratio must be finite and >= 1, got " + v);
         }},
        {"--inner-distance-level", "L", "Landmarks (an addition to the paper)",
         "level of the lattice on which F is computed, 1.." +
             std::to_string(MAX_INNER_DISTANCE_LEVEL) + " (" +
             std::to_string(MAX_INNER_DISTANCE_LEVEL_3D) + " in 3D); 0: the default (" +
             both(double(DEFAULT_INNER_DISTANCE_LEVEL_3D), double(DEFAULT_INNER_DISTANCE_LEVEL_2D)) +
             ")",
         [](O& o, const std::string& v) {
             const int l = parseInt("--inner-distance-level", v);
             if (l < 0 || l > MAX_INNER_DISTANCE_LEVEL)
                 throw UsageError("--inner-distance-level must be in [0, " +
                                  std::to_string(MAX_INNER_DISTANCE_LEVEL) + "], got " + v);
             o.innerDistanceLevel = l;
         }},
        {"--inner-distance-levels", "N", "Landmarks (an addition to the paper)",
         "levels, from the first, at which the inner-distance term acts, >= 0; 0: every level "
         "(default " +
             std::to_string(d.innerDistanceLevels) + ")",
         [](O& o, const std::string& v) {
             o.innerDistanceLevels = parseInt("--inner-distance-levels", v);
             if (o.innerDistanceLevels < 0)
                 throw UsageError("--inner-distance-levels must be >= 0, got " + v);
         }},
        {"--max-iterations", "N", "Descent",
         "iteration limit per level (default " + std::to_string(d.maxIterations) + ")",
         [](O& o, const std::string& v) { o.maxIterations = parseInt("--max-iterations", v); }},
        {"--energy-tolerance", "X", "Descent",
         "the last level ends when the energy fell by less than X (relative, its constant part "
         "excluded) over 5 iterations (default " + formatNumber(d.energyTolerance) + ")",
         [](O& o, const std::string& v) { o.energyTolerance = parseDouble("--energy-tolerance", v); }},
        {"--settle-tolerance", "X", "Descent",
         "... or when its last 5 iterations lowered the energy by less than X times what the "
         "level has lowered it so far (default " + formatNumber(d.settleTolerance) + ": off)",
         [](O& o, const std::string& v) { o.settleTolerance = parseDouble("--settle-tolerance", v); }},
        {"--surface-tolerance", "X", "Descent",
         "... or, at the last --surface-levels levels, when the source surface moved by less than X "
         "cells (path length of the mean over its vertices) over 5 iterations (default " +
             both(MatchOptions::defaults(3).multiscale.surfaceTolerance,
                  MatchOptions::defaults(2).multiscale.surfaceTolerance) + "; 0: off)",
         [](O& o, const std::string& v) { o.surfaceTolerance = parseDouble("--surface-tolerance", v); }},
        {"--surface-levels", "N", "Descent",
         "the surface test applies at the last N levels only (default " + std::to_string(d.surfaceLevels) + ")",
         [](O& o, const std::string& v) { o.surfaceLevels = parseInt("--surface-levels", v); }},
        {"--surface-from-level", "L", "Descent",
         "... and at every level >= L (default " + std::to_string(d.surfaceFromLevel) +
             ": only the last --surface-levels; 7 at levels 4..8 ends level 7 too, faster but "
             "less consistent: docs/performance.md)",
         [](O& o, const std::string& v) {
             o.surfaceFromLevel = parseInt("--surface-from-level", v);
         }},
        {"--tolerance-coarsening", "F", "Descent",
         "level l divides the energy, settle and surface tolerances by F^(last level - l): coarse levels, "
         "where iterations are cheap, converge further (default " + formatNumber(d.toleranceCoarsening) + ")",
         [](O& o, const std::string& v) { o.toleranceCoarsening = parseDouble("--tolerance-coarsening", v); }},
        {"--iteration-coarsening", "F", "Descent",
         "an addition to the paper: level l runs at most --max-iterations times F^(last level - "
         "l) iterations, so that coarse levels, whose iterations cost a fraction of the finest "
         "one's, are not stopped before they converge, >= 1 (default 1: one limit; "
         "docs/numerics.md \"Iteration limit per level\")",
         [](O& o, const std::string& v) {
             o.iterationCoarsening = parseDouble("--iteration-coarsening", v);
         }},
        {"--gradient-tolerance", "X", "Descent",
         "... or when the H1 gradient norm fell below X times its initial value (default " +
             formatNumber(d.gradientTolerance) + ")",
         [](O& o, const std::string& v) {
             o.gradientTolerance = parseDouble("--gradient-tolerance", v);
         }},
        {"--metric-tau", "X", "Descent",
         "weight of the H1 metric M + tau L as a factor of sigma^2, >= 0 (default " +
             both(MatchOptions::defaults(3).multiscale.metricTauFactor,
                  MatchOptions::defaults(2).multiscale.metricTauFactor) +
             "; --preset paper: " +
             formatNumber(MatchOptions::paper(2).multiscale.metricTauFactor) + ")",
         [](O& o, const std::string& v) { o.metricTau = parseDouble("--metric-tau", v); }},
        {"--optimizer", "NAME", "Descent",
         "ncg (the paper's nonlinear conjugate gradients) or lbfgs (limited-memory BFGS in the "
         "same metric) (default " + std::string(solver::toString(d.method)) + ")",
         [](O& o, const std::string& v) {
             if (v != "ncg" && v != "lbfgs") {
                 throw UsageError("--optimizer expects 'ncg' or 'lbfgs', got '" + v + "'");
             }
             o.method = solver::parseDescentMethod(v);
         }},
        {"--initial-step", "RULE", "Descent",
         "first line-search trial of an iteration: 'grow' (twice the last step) or 'slope' (the "
         "last step scaled by the ratio of the directional derivatives) (default " +
             std::string(d.initialStepFromSlope ? "slope" : "grow") + ")",
         [](O& o, const std::string& v) {
             if (v != "grow" && v != "slope") {
                 throw UsageError("--initial-step expects 'grow' or 'slope', got '" + v + "'");
             }
             o.initialStepFromSlope = v == "slope";
         }},
        {"--trial-growth", "X", "Descent",
         "the 'grow' rule's factor: the first trial of a line search is X times the last accepted "
         "step (also the cap of the 'slope' rule), >= 1 (default " +
             formatNumber(d.trialGrowth) + ")",
         [](O& o, const std::string& v) { o.trialGrowth = parseDouble("--trial-growth", v); }},
        {"--metric-tolerance", "X", "Descent",
         "relative residual of the conjugate-gradient solve of the metric (default " +
             formatNumber(d.metricTolerance) + ")",
         [](O& o, const std::string& v) {
             o.metricTolerance = parseDouble("--metric-tolerance", v);
         }},
        {"--second-path", "on|off", "Descent",
         "an addition to the paper: when more than --second-path-share of M1 ends farther than "
         "sigma of the finest level from M2 (part of the source left behind by the coarse "
         "levels), run the levels again with " +
             formatNumber(SECOND_PATH_VOLUME_FACTOR) +
             "x the volume weight below the finest level, and once more with " +
             formatNumber(SECOND_PATH_VOLUME_FACTOR * SECOND_PATH_VOLUME_FACTOR) +
             "x if that path too leaves it behind; keep the result whose finest level ends at "
             "the lowest energy (docs/numerics.md) (default " +
             std::string(MatchOptions::defaults(3).secondPath ? "on" : "off") +
             "; --preset paper: off)",
         [](O& o, const std::string& v) { o.secondPath = parseOnOff("--second-path", v); }},
        {"--second-path-share", "X", "Descent",
         "the share of M1's vertices (with --second-path-target on: or of M2's from phi(M1)), "
         "in [0, 1], that must end farther than sigma from M2 for --second-path to run another "
         "path (default " +
             formatNumber(DEFAULT_SECOND_PATH_SHARE) + ")",
         [](O& o, const std::string& v) {
             o.secondPathShare = parseDouble("--second-path-share", v);
         }},
        {"--second-path-target", "on|off", "Descent",
         "an addition to the paper: with --second-path, also run another path when more than "
         "--second-path-share of M2 ends farther than sigma from phi(M1) (part of the target "
         "not reached; the target residual of the report) (default off: it reaches the target "
         "at a higher correspondence error on the benchmark, docs/numerics.md)",
         [](O& o, const std::string& v) {
             o.secondPathTarget = parseOnOff("--second-path-target", v);
         }},
        {"--strict", nullptr, "Descent",
         "exit with code 4 if the finest level did not converge (outputs are still written)",
         [](O& o, const std::string&) { o.strict = true; }},
        {"--quiet", nullptr, "Execution", "no progress on stderr (errors are still printed)",
         [](O& o, const std::string&) { o.quiet = true; }},
        {"--progress-every", "N", "Execution",
         "print a progress line every N iterations (default " +
             std::to_string(d.progressEvery) + ")",
         [](O& o, const std::string& v) { o.progressEvery = parseInt("--progress-every", v); }},
        {"--threads", "N", "Execution", "number of threads, 0 = all cores (default 0)",
         [](O& o, const std::string& v) { o.threads = parseThreads(v); }},
    };
    // clang-format on
}

/// Applies a --config file (ConfigFile.h): each setting as its option would be.
/// @throw as readConfig; UsageError for a value its option rejects
void
applyConfig(const std::string& path, MatchCliOptions& o)
{
    const std::vector<Option<MatchCliOptions>> table = matchOptionTable();
    for (const ConfigSetting& setting : readConfig(path)) {
        for (const Option<MatchCliOptions>& opt : table) {
            if (canonicalName(opt.name) != setting.option) continue;
            try {
                opt.apply(o, setting.value);
            } catch (const UsageError& e) {
                throw UsageError("--config '" + path + "', key '" + setting.key + "': " + e.what());
            }
        }
    }
}

MatchCliOptions
parseMatchOptions(int argc, const char* const* argv, int first)
{
    MatchCliOptions o;
    o.commandLine = commandLine(argc, argv);
    // --config first, whatever its position: the command line overrides it.
    for (int i = first; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--") break;
        if (arg == "--config" && i + 1 < argc) o.config = argv[i + 1];
        if (arg.rfind("--config=", 0) == 0) o.config = arg.substr(9);
    }
    if (!o.config.empty()) applyConfig(o.config, o);
    // --landmarks on the command line replaces the config's pair (the option appends).
    std::vector<std::string> configLandmarks;
    std::swap(configLandmarks, o.landmarkFiles);
    const std::vector<std::string> positional =
        parseOptions(matchOptionTable(), argc, argv, first, o);
    if (o.landmarkFiles.empty()) o.landmarkFiles = configLandmarks;
    assignInputs(positional, o.source, o.target, "expected SOURCE TARGET");
    if (o.outDir.empty()) throw UsageError("missing the output directory: -o OUTDIR");
    if (!o.grid.empty() && (!o.sourceGrid.empty() || !o.targetGrid.empty())) {
        throw UsageError("--grid cannot be combined with --source-grid or --target-grid");
    }
    if (o.minLevel && o.maxLevel && *o.minLevel > *o.maxLevel) {
        throw UsageError("the first level (" + std::to_string(*o.minLevel) +
                         ") is finer than the last (" + std::to_string(*o.maxLevel) + ")");
    }
    for (const auto& [name, path] : {std::pair<std::string, std::string>{
                                         o.sourceGrid.empty() ? o.grid : o.sourceGrid, o.source},
                                     {o.targetGrid.empty() ? o.grid : o.targetGrid, o.target}}) {
        if (!name.empty() && isShapeFile(path) && !isLevelSetFile(path)) {
            throw UsageError("--grid applies to .vdb inputs, not to '" + path + "'");
        }
    }
    checkIsoValueInputs(o.isoValue, o.source, o.target);
    if (o.progressEvery < 1) throw UsageError("--progress-every must be >= 1");
    if (o.threads < 0) throw UsageError("--threads must be >= 0");
    if (o.hessianSmoothing < 0) throw UsageError("--hessian-smoothing must be >= 0");
    if (!(o.iterationCoarsening >= 1 && std::isfinite(o.iterationCoarsening)))
        throw UsageError("--iteration-coarsening must be a finite number >= 1");
    if (o.noiseSmoothing && !(*o.noiseSmoothing >= 0 && std::isfinite(*o.noiseSmoothing)))
        throw UsageError("--noise-smoothing must be a finite number >= 0");
    if (o.latticeNoiseSmoothing &&
        !(*o.latticeNoiseSmoothing >= 0 && std::isfinite(*o.latticeNoiseSmoothing)))
        throw UsageError("--lattice-noise-smoothing must be a finite number >= 0");
    if (o.noiseBending && !(*o.noiseBending >= 0 && std::isfinite(*o.noiseBending)))
        throw UsageError("--noise-bending must be a finite number >= 0");
    if (o.anchorNoiseTolerance &&
        !(*o.anchorNoiseTolerance >= 0 && std::isfinite(*o.anchorNoiseTolerance)))
        throw UsageError("--anchor-noise-tolerance must be a finite number >= 0");
    if (o.maxIterations < 0) throw UsageError("--max-iterations must be >= 0");
    if (!o.init.empty() && !o.warmStart.empty()) {
        throw UsageError("--init (this pair's earlier result) and --warm-start (another pair's) "
                         "cannot be combined");
    }
    if (o.warmStartLevel && o.warmStart.empty()) {
        throw UsageError("--warm-start-level needs --warm-start");
    }
    return o;
}

////////////////////////////////////////////////////////////////////////////////
// Progress

std::string
termsText(const EnergyTerms& t)
{
    return "match " + fixed("%.3e", t.match[0] + t.match[1]) + " mem " +
           fixed("%.3e", t.mem[0] + t.mem[1]) + " bend " + fixed("%.3e", t.bend[0] + t.bend[1]) +
           " vol " + fixed("%.3e", t.vol[0] + t.vol[1]) +
           (t.landmark != 0 ? " landmarks " + fixed("%.3e", t.landmark) : std::string()) +
           (t.innerDistance != 0 ? " inner " + fixed("%.3e", t.innerDistance) : std::string());
}

/// Progress on stderr with an estimate of the time left: a level is assumed to cost the time
/// of the previous one times the ratio of their unknowns, and each later level 2^(d-1) times
/// the one before (the fine cells follow the surfaces). A level that the surface test ends
/// (the finest, in 3D) is assumed to take SURFACE_LEVEL_ITERATIONS iterations instead
/// (5-12 measured, docs/performance.md).
class ProgressPrinter
{
public:
    static constexpr double SURFACE_LEVEL_ITERATIONS = 12;

    /// @param firstSurfaceLevel  the first level the surface test may end (> maxLevel: none)
    ProgressPrinter(std::ostream& err, const MatchCliOptions& o, int dim, int minLevel,
                    int maxLevel, int firstSurfaceLevel)
        : mErr(err), mO(o), mDim(dim), mMinLevel(minLevel), mMaxLevel(maxLevel),
          mFirstSurfaceLevel(firstSurfaceLevel), mHooks(currentHooks())
    {
    }

    void message(const std::string& text)
    {
        if (!mO.quiet) mErr << PROGRAM << ": " << text << std::endl;
        emit(ProgressEvent::Kind::Message, 0, 0, 0, text);
    }

    void levelStart(int level, const LatticeSummary& s, double fieldSeconds, double latticeSeconds)
    {
        if (mLastLevelSeconds > 0 && mLastUnknowns > 0) {
            const double ratio = double(s.unknowns) / double(mLastUnknowns);
            mFullLevel = mLastLevelSeconds * ratio;
            mIteration = mLastIterationSeconds * ratio;
            mLevelEstimate =
                level >= mFirstSurfaceLevel ? SURFACE_LEVEL_ITERATIONS * mIteration : mFullLevel;
        } else {
            mLevelEstimate = -1;
        }
        mLastUnknowns = s.unknowns;
        mLevelStart = Clock::now();
        mLevelPrep = fieldSeconds + latticeSeconds;
        const double fraction = s.denseNodes ? double(s.nodes) / double(s.denseNodes) : 1.0;
        const std::string text =
            "level " + std::to_string(level) + ": h = 2^-" + std::to_string(level) + ", " +
            std::to_string(s.cells) + " cells, " + std::to_string(s.unknowns) + " unknowns (" +
            std::to_string(s.nodes) + " nodes = " + fixed("%.1f", 100.0 * fraction) + "% of the " +
            std::to_string(s.denseNodes) + " dense nodes, " + std::to_string(s.hangingNodes) +
            " hanging); fields " + fixed("%.2fs", fieldSeconds) + ", lattice " +
            fixed("%.2fs", latticeSeconds);
        if (!mO.quiet) mErr << PROGRAM << ": " << text << std::endl;
        emit(ProgressEvent::Kind::LevelStart, level, 0, 0, text);
    }

    void iteration(const solver::IterationInfo& i)
    {
        const bool print = !mO.quiet && i.iteration % mO.progressEvery == 0;
        if (!print && !(mHooks && mHooks->progress)) return;
        const std::string text =
            "level " + std::to_string(i.level) + " it " + fixed("%4.0f", i.iteration) + "  E " +
            fixed("%.6e", i.energy) + " (" + termsText(i.terms) + ")  |g| " +
            fixed("%.2e", i.gradNorm) + "  step " + fixed("%.2e", i.step) + "  " +
            (i.surfaceMotion >= 0
                 ? "surface moved " + fixed("%.3g", std::ldexp(i.surfaceMotion, i.level)) + " h  "
                 : std::string()) +
            duration(secondsSince(mStart)) + timeLeft(i.level);
        if (print) mErr << PROGRAM << ": " << text << std::endl;
        emit(ProgressEvent::Kind::Iteration, i.level, i.iteration, i.energy, text);
    }

    void levelEnd(const LevelSummary& s)
    {
        mLastLevelSeconds = s.report.elapsedSeconds + mLevelPrep;
        mLastIterationSeconds = s.report.elapsedSeconds / std::max(1, s.report.iterations);
        const solver::Report& r = s.report;
        std::string how = solver::toString(r.status);
        if (r.status == solver::Status::Converged) {
            how += std::string(" (") + solver::toString(r.convergedBy) + ")";
        }
        const std::string text = "level " + std::to_string(s.level) + " done: " + how + " after " +
                                 std::to_string(r.iterations) + " iterations, E " +
                                 fixed("%.6e", r.energy) + " (" + termsText(r.terms) +
                                 "), min det " + fixed("%.3g", r.minJacobian) + ", " +
                                 fixed("%.1fs", r.elapsedSeconds);
        if (!mO.quiet) mErr << PROGRAM << ": " << text << std::endl;
        emit(ProgressEvent::Kind::LevelEnd, s.level, r.iterations, r.energy, text);
    }

private:
    void emit(ProgressEvent::Kind kind, int level, int iteration, double energy,
              const std::string& text) const
    {
        if (!mHooks || !mHooks->progress) return;
        ProgressEvent e;
        e.kind = kind;
        e.level = level;
        e.firstLevel = mMinLevel;
        e.lastLevel = mMaxLevel;
        e.iteration = iteration;
        e.energy = energy;
        e.elapsedSeconds = secondsSince(mStart);
        e.secondsLeft = level > 0 ? secondsLeft(level) : -1;
        e.text = text;
        mHooks->progress(e);
    }

    std::string timeLeft(int level) const
    {
        const double left = secondsLeft(level);
        return left < 0 ? "" : "  left ~" + duration(left);
    }

    /// The estimate of the time left while at @a level, or -1 before there is one.
    double secondsLeft(int level) const
    {
        if (mLevelEstimate <= 0) return -1;
        const double growth = std::pow(2.0, mDim - 1);
        double left = std::max(0.0, mLevelEstimate - secondsSince(mLevelStart));
        double full = mFullLevel, iteration = mIteration, prep = mLevelPrep;
        for (int l = level + 1; l <= mMaxLevel; ++l) {
            full *= growth;
            iteration *= growth;
            prep *= growth;
            left += l >= mFirstSurfaceLevel ? prep + SURFACE_LEVEL_ITERATIONS * iteration : full;
        }
        return left;
    }

    std::ostream& mErr;
    const MatchCliOptions& mO;
    int mDim, mMinLevel, mMaxLevel, mFirstSurfaceLevel;
    const RunHooks* mHooks;
    Clock::time_point mStart = Clock::now(), mLevelStart = Clock::now();
    double mLevelEstimate = -1, mLastLevelSeconds = 0, mLevelPrep = 0;
    double mLastIterationSeconds = 0, mFullLevel = 0, mIteration = 0;
    std::size_t mLastUnknowns = 0;
};

////////////////////////////////////////////////////////////////////////////////
// Outputs

Json
pairJson(const Real* v)
{
    return Json::array({v[0], v[1]});
}

Json
termsJson(const EnergyTerms& t)
{
    return Json{{"match", pairJson(t.match)}, {"mem", pairJson(t.mem)},
                {"bend", pairJson(t.bend)},   {"vol", pairJson(t.vol)},
                {"landmarks", t.landmark},    {"innerDistance", t.innerDistance},
                {"total", t.total()}};
}

template <int D>
const Surface<D>&
surfaceOf(const Shape& in)
{
    return in.get<D>();
}

/// What was written besides deformation.vdb, for report.json.
struct ExtraOutputs
{
    std::vector<std::string> files; ///< every file written, in order
    bool inverse = false;
    std::size_t inverseNodes = 0, inverseFailures = 0;
    double inverseMaxResidual = 0, inverseSeconds = 0;
    bool jacobian = false;
    double detMin = 1, detMax = 1, jacobianSeconds = 0;
    std::vector<std::string> halfRefused; ///< --half files kept in float (rounding would fold)
};

/// min det D of the grid's map after rounding its values to half precision (what --half stores).
double
minDeterminantAsHalf(const openvdb::Vec3SGrid& grid)
{
    openvdb::Vec3SGrid::Ptr rounded = grid.deepCopy();
    for (auto v = rounded->beginValueOn(); v; ++v) {
        const openvdb::Vec3s x = *v;
        v.setValue(openvdb::Vec3s(float(openvdb::math::half(x[0])),
                                  float(openvdb::math::half(x[1])),
                                  float(openvdb::math::half(x[2]))));
    }
    return eval::jacobianStats(DeformationField(rounded)).min;
}

/// report.json (docs/cli.md): keys in a fixed order, numbers in their shortest round-trip form,
/// non-finite numbers as null.
/// Peak resident memory of this process so far, MB (getrusage).
double
peakMemoryMB()
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return double(ru.ru_maxrss) / 1024.0; // kilobytes on Linux
}

template <int D>
std::string
reportJson(const MatchCliOptions& o, const MatchOptions& opts, const Shape (&in)[2],
           const MatchResult<D>& r, const std::string& status, double writeSeconds,
           const ExtraOutputs& extra, const InitialDeformation* init,
           const std::string& warmFallback)
{
    const EnergyParameters& p = opts.multiscale.energy;
    const solver::DescentOptions& descent = opts.multiscale.descent;
    Json j;
    j["command"] = "match";
    j["version"] = VDBMATCH_VERSION;
    j["commandLine"] = o.commandLine;
    j["status"] = status;
    j["dimension"] = D;
    j["source"] = shapeJson(in[0]);
    j["target"] = shapeJson(in[1]);
    j["placement"] = Json{{"worldOrigin", jsonVec(r.placement.worldOrigin)},
                          {"scale", r.placement.scale},
                          {"margin", r.placement.margin}};
    if (init) {
        j["init"] = Json{
            {"path", o.init.empty() ? o.warmStart : o.init},
            {"kind", o.warmStart.empty() ? "init" : "warm-start"},
            {"used", warmFallback.empty()},
            {"fallback", warmFallback.empty() ? Json() : Json(warmFallback)},
            {"levels", std::to_string(init->firstLevel) + ".." + std::to_string(init->finestLevel)},
            {"gridLevel", init->gridLevel},
            {"interrupted", init->interrupted},
            {"startLevel", opts.multiscale.minLevel},
            {"lipschitz", init->start->lipschitz}};
    } else {
        j["init"] = nullptr;
    }
    Json& params = j["parameters"];
    params["preset"] = o.preset;
    params["energy"] = toString(opts.multiscale.kind);
    params.update(energyParametersJson(p));
    params["coarseMembraneFactor"] = opts.multiscale.coarseMembraneFactor;
    params["membraneSaturationLevels"] = opts.multiscale.membraneSaturationLevels;
    params["coarseVolumeFactor"] = opts.multiscale.coarseVolumeFactor;
    params["coarseSigmaFactor"] = opts.multiscale.coarseSigmaFactor;
    params.update(
        Json{{"hessianSmoothing", opts.sampler.fields.hessianSmoothing},
             {"noiseSmoothing", opts.hessianNoiseFactor},
             {"latticeNoiseSmoothing", opts.hessianLatticeNoiseFactor},
             {"noiseBending", opts.noiseBendingPasses},
             {"minLevel", opts.coarsestLevel > 0 ? opts.coarsestLevel : opts.multiscale.minLevel},
             {"maxLevel", opts.multiscale.maxLevel},
             {"margin", opts.margin},
             {"refinementMarginCells", opts.refinementMarginCells},
             {"metricTauFactor", opts.multiscale.metricTauFactor},
             {"optimizer", solver::toString(descent.method)},
             {"initialStep", descent.initialStepFromSlope ? "slope" : "grow"},
             {"trialGrowth", descent.lineSearch.grow},
             {"metricTolerance", opts.multiscale.metric.cgTolerance},
             {"maxIterations", descent.maxIterations},
             {"energyTolerance", descent.energyTolerance},
             {"settleTolerance", descent.settleTolerance},
             {"surfaceTolerance", opts.multiscale.surfaceTolerance},
             {"surfaceLevels", opts.multiscale.surfaceLevels},
             {"surfaceFromLevel", opts.multiscale.surfaceFromLevel},
             {"toleranceCoarsening", opts.multiscale.toleranceCoarsening},
             {"iterationCoarsening", opts.multiscale.iterationCoarsening},
             {"relativeGradientTolerance", descent.relativeGradientTolerance},
             {"landmarkWeight", opts.landmarkWeight},
             {"autoLandmarks", opts.autoLandmarks ? "on" : "off"},
             {"autoLandmarkLevels", opts.autoLandmarkLevels},
             {"autoLandmarkMinMotion", opts.autoLandmarkMinMotion},
             {"autoAnchors", opts.autoAnchors ? "on" : "off"},
             {"landmarkAnchors", opts.landmarkAnchors ? "on" : "off"},
             {"anchorWeight", opts.anchorWeight},
             {"anchorCount", opts.anchorOptions.count},
             {"anchorRadius", opts.anchorOptions.radius},
             {"anchorTolerance", opts.anchorOptions.tolerance},
             {"anchorNoiseTolerance", opts.anchorNoiseFactor},
             {"rigidLimbWeight", opts.rigidLimbWeight},
             {"rigidLimbMinMotion", opts.rigidLimbMinMotion},
             {"rigidLimbAnchorRadius", opts.rigidLimbAnchorRadius},
             {"rigidLimbCount", opts.rigidLimbOptions.count},
             {"rigidLimbReach", opts.rigidLimbOptions.reach},
             {"rigidSegment", opts.rigidLimbOptions.segmentTo > 0
                                  ? formatNumber(opts.rigidLimbOptions.segmentFrom) + "," +
                                        formatNumber(opts.rigidLimbOptions.segmentTo)
                                  : std::string("off")},
             {"rigidSegmentMinAngle", opts.rigidLimbOptions.segmentMinAngle},
             {"rigidSegmentTipMotion", opts.rigidLimbOptions.segmentMaxTipMotion},
             {"innerDistanceWeight", opts.innerDistanceWeight},
             {"innerDistanceTolerance", opts.innerDistanceTolerance},
             {"innerDistanceRatio", opts.innerDistanceRatio},
             {"innerDistanceLevel", opts.innerDistanceLevel},
             {"innerDistanceLevels", opts.innerDistanceLevels},
             {"secondPath", opts.secondPath ? "on" : "off"},
             {"secondPathShare", opts.secondPathShare},
             {"secondPathTarget", opts.secondPathTarget ? "on" : "off"}});
    if (r.autoLandmarks.requested) {
        const AutoLandmarkSummary& a = r.autoLandmarks;
        Json pairs = Json::array();
        for (std::size_t k = 0; k < a.source.size(); ++k) {
            pairs.push_back(
                Json{{"source", jsonVec(a.source[k])}, {"target", jsonVec(a.target[k])}});
        }
        j["autoLandmarks"] =
            Json{{"used", a.used},
                 {"reason", a.used ? Json() : Json(a.reason)},
                 {"sourceExtremities", a.sourceExtremities},
                 {"targetExtremities", a.targetExtremities},
                 {"paired", a.paired},
                 {"maxMotion", a.maxMotion},
                 {"minMotion", a.minMotion},
                 {"distortion", a.distortion},
                 {"candidates", a.candidates},
                 {"lastLevel", a.lastLevel},
                 {"pairs", pairs},
                 {"anchors", a.anchors.size()},
                 {"anchorCoincidentShare", a.anchorCoincidentShare},
                 {"anchorReason", a.anchorReason.empty() ? Json() : Json(a.anchorReason)},
                 {"anchorTolerance", a.anchorTolerance},
                 {"anchorRadius", a.anchorRadius},
                 {"seconds", a.seconds}};
        if (!a.limbs.empty()) {
            Json limbs = Json::array();
            for (const RigidLimbFit& l : a.limbs) {
                limbs.push_back(Json{{"extremity", l.extremity},
                                     {"segment", l.segment},
                                     {"used", l.used},
                                     {"reason", l.used ? Json() : Json(l.reason)},
                                     {"joint", l.joint()},
                                     {"sourceJoint", l.sourceJoint},
                                     {"targetJoint", l.targetJoint},
                                     {"sourceVertices", l.sourceVertices},
                                     {"targetVertices", l.targetVertices},
                                     {"residual", l.residual},
                                     {"angleDegrees", l.angle},
                                     {"axialTurnDegrees", l.axialTurn}});
            }
            j["autoLandmarks"]["rigidLimbs"] = limbs;
            j["autoLandmarks"]["rigidLimbPoints"] = a.limbSource.size();
            j["autoLandmarks"]["rigidLimbMinMotion"] = a.limbMinMotion;
        }
        if (a.used) {
            j["autoLandmarks"]["startMeanWorld"] = r.landmarks.startMeanWorld;
            j["autoLandmarks"]["meanWorld"] = r.landmarks.meanWorld;
        }
    }
    if (r.innerDistance.requested) {
        const InnerDistanceSummary& f = r.innerDistance;
        j["innerDistance"] =
            Json{{"used", f.used},           {"reason", f.used ? Json() : Json(f.reason)},
                 {"weight", f.weight},       {"tolerance", f.tolerance},
                 {"level", f.level},         {"ratio", f.ratio},
                 {"points", f.points},       {"share", f.share},
                 {"startMean", f.startMean}, {"startBeyond", f.startBeyond},
                 {"mean", f.mean},           {"beyond", f.beyond},
                 {"seconds", f.seconds}};
    }
    if (!o.landmarkFiles.empty()) {
        params["landmarks"] = o.landmarkFiles;
        j["landmarks"] = Json{{"source", o.landmarkFiles[0]},
                              {"target", o.landmarkFiles[1]},
                              {"count", r.landmarks.count},
                              {"startMeanWorld", r.landmarks.startMeanWorld},
                              {"startMaxWorld", r.landmarks.startMaxWorld},
                              {"meanWorld", r.landmarks.meanWorld},
                              {"maxWorld", r.landmarks.maxWorld}};
    }
    const auto levelJson = [&opts](const LevelSummary& l) {
        const solver::Report& rep = l.report;
        const double h = std::ldexp(1.0, -l.level);
        return Json{
            {"level", l.level},
            {"h", h},
            {"sigma", opts.multiscale.energyAt(l.level).sigmaFactor * h},
            {"cells", l.lattice.cells},
            {"simplices", l.lattice.simplices},
            {"nodes", l.lattice.nodes},
            {"unknowns", l.lattice.unknowns},
            {"hangingNodes", l.lattice.hangingNodes},
            {"denseNodes", l.lattice.denseNodes},
            {"nodeFractionOfDense",
             l.lattice.denseNodes ? double(l.lattice.nodes) / double(l.lattice.denseNodes) : 0.0},
            {"cellsPerSize", l.lattice.cellsPerLog2Size},
            {"status", solver::toString(rep.status)},
            {"convergedBy", solver::toString(rep.convergedBy)},
            {"iterations", rep.iterations},
            {"energyEvaluations", rep.energyEvaluations},
            {"gradientEvaluations", rep.gradientEvaluations},
            {"metricIterations", rep.metricIterations},
            {"restarts", rep.restarts},
            {"initialEnergy", rep.initialEnergy},
            {"energy", rep.energy},
            {"terms", termsJson(rep.terms)},
            {"bendingFactor", l.bendingFactor},
            {"gradNorm", rep.gradNorm},
            {"minJacobian", rep.minJacobian},
            {"bandSimplices", rep.terms.bandSimplices},
            {"coarseBandSimplices", rep.terms.coarseBandSimplices},
            {"seconds", Json{{"fields", l.fieldSeconds},
                             {"lattice", l.latticeSeconds},
                             {"descent", rep.elapsedSeconds}}}};
    };
    Json levels = Json::array();
    for (const LevelSummary& l : r.levels)
        levels.push_back(levelJson(l));
    j["levels"] = levels;
    if (opts.hessianNoiseFactor > 0) {
        j["noise"] = Json{{"source", r.shapeNoise[0]},
                          {"target", r.shapeNoise[1]},
                          {"lattice", {r.latticeNoise[0], r.latticeNoise[1]}},
                          {"smoothingLength", {r.smoothingLength[0], r.smoothingLength[1]}}};
    }
    if (r.secondPath.requested) {
        const SecondPathSummary& sp = r.secondPath;
        j["secondPath"] = Json{{"ran", sp.ran},
                               {"reason", sp.ran ? Json() : Json(sp.reason)},
                               {"farShare", sp.farShare},
                               {"targetFarShare", sp.targetFarShare},
                               {"threshold", sp.threshold}};
        if (sp.ran) {
            Json paths = Json::array();
            for (std::size_t k = 0; k < sp.paths.size(); ++k) {
                const PathSummary& path = sp.paths[k];
                Json discarded = Json::array();
                for (const LevelSummary& l : path.levels)
                    discarded.push_back(levelJson(l));
                paths.push_back(Json{{"coarseVolumeFactor", path.coarseVolumeFactor},
                                     {"energy", path.energy},
                                     {"farShare", path.farShare},
                                     {"targetFarShare", path.targetFarShare},
                                     {"levels", k == sp.kept ? Json() : discarded}});
            }
            j["secondPath"].update(
                Json{{"paths", paths}, {"kept", sp.kept}, {"seconds", sp.seconds}});
        }
    }
    const solver::Report* last = r.levels.empty() ? nullptr : &r.levels.back().report;
    j["result"] = Json{{"energy", last ? last->energy : INF},
                       {"terms", termsJson(last ? last->terms : EnergyTerms())},
                       {"minJacobian", r.minJacobian},
                       {"residual", residualJson(r.residual, in[0])},
                       {"targetResidual", residualJson(r.targetResidual, in[1])},
                       {"seconds", Json{{"match", r.totalSeconds}, {"write", writeSeconds}}},
                       {"peakMemoryMB", peakMemoryMB()}};
    if (extra.inverse) {
        j["inverse"] = Json{{"nodes", extra.inverseNodes},
                            {"failures", extra.inverseFailures},
                            {"maxResidualWorld", extra.inverseMaxResidual},
                            {"seconds", extra.inverseSeconds}};
    }
    if (extra.jacobian) {
        j["jacobian"] = Json{{"grid", o.logJacobian ? LOG_JACOBIAN_GRID_NAME : JACOBIAN_GRID_NAME},
                             {"detMin", extra.detMin},
                             {"detMax", extra.detMax},
                             {"seconds", extra.jacobianSeconds}};
    }
    j["half"] = o.half;
    if (!extra.halfRefused.empty()) j["halfRefused"] = extra.halfRefused;
    j["outputs"] = extra.files;
    return dumpJson(j);
}

template <int D>
int
runMatch(const MatchCliOptions& o, const Shape (&in)[2], std::ostream& out, std::ostream& err)
{
    const Clock::time_point start = Clock::now();
    MatchOptions opts = o.preset == "paper" ? MatchOptions::paper(D) : MatchOptions::defaults(D);
    EnergyParameters& p = opts.multiscale.energy;
    if (o.cMatch) p.cMatch = *o.cMatch;
    if (o.cMem) p.cMem = *o.cMem;
    if (o.coarseMembraneFactor) opts.multiscale.coarseMembraneFactor = *o.coarseMembraneFactor;
    if (o.membraneSaturation) p.membraneSaturation = *o.membraneSaturation;
    if (o.membraneSaturationLevels)
        opts.multiscale.membraneSaturationLevels = *o.membraneSaturationLevels;
    if (o.cBend) p.cBend = *o.cBend;
    if (o.cVol) p.cVol = *o.cVol;
    if (o.coarseVolumeFactor) opts.multiscale.coarseVolumeFactor = *o.coarseVolumeFactor;
    if (o.coarseSigmaFactor) opts.multiscale.coarseSigmaFactor = *o.coarseSigmaFactor;
    if (o.q) p.q = *o.q;
    if (o.theta) p.theta = *o.theta;
    p.tau = o.tau;
    opts.multiscale.kind = o.kind;
    if (o.minLevel) opts.multiscale.minLevel = *o.minLevel;
    if (o.maxLevel) opts.multiscale.maxLevel = *o.maxLevel;
    if (opts.multiscale.minLevel > opts.multiscale.maxLevel) {
        throw UsageError("the first level (" + std::to_string(opts.multiscale.minLevel) +
                         ") is finer than the last (" + std::to_string(opts.multiscale.maxLevel) +
                         ")");
    }
    if (opts.multiscale.maxLevel > 12 || opts.multiscale.minLevel < 1) {
        OPENVDB_THROW(openvdb::ValueError, "levels must be in [1, 12], got "
                                               << opts.multiscale.minLevel << ".."
                                               << opts.multiscale.maxLevel);
    }
    if (o.metricTau) opts.multiscale.metricTauFactor = *o.metricTau;
    opts.multiscale.metric.cgTolerance = o.metricTolerance;
    opts.multiscale.descent.method = o.method;
    opts.multiscale.descent.initialStepFromSlope = o.initialStepFromSlope;
    opts.multiscale.descent.lineSearch.grow = o.trialGrowth;
    opts.multiscale.descent.maxIterations = o.maxIterations;
    opts.multiscale.descent.energyTolerance = o.energyTolerance;
    opts.multiscale.descent.settleTolerance = o.settleTolerance;
    opts.multiscale.toleranceCoarsening = o.toleranceCoarsening;
    opts.multiscale.iterationCoarsening = o.iterationCoarsening;
    if (o.surfaceTolerance) opts.multiscale.surfaceTolerance = *o.surfaceTolerance;
    opts.multiscale.surfaceLevels = o.surfaceLevels;
    opts.multiscale.surfaceFromLevel = o.surfaceFromLevel;
    opts.multiscale.descent.relativeGradientTolerance = o.gradientTolerance;
    opts.margin = o.margin;
    opts.refinementMarginCells = o.refinementMargin;
    opts.sampler.fields.hessianSmoothing = o.hessianSmoothing;
    if (o.noiseSmoothing) opts.hessianNoiseFactor = *o.noiseSmoothing;
    if (o.latticeNoiseSmoothing) opts.hessianLatticeNoiseFactor = *o.latticeNoiseSmoothing;
    if (o.noiseBending) opts.noiseBendingPasses = *o.noiseBending;
    // --landmarks A B: the same number of points in each, in world units of the inputs.
    if (!o.landmarkFiles.empty()) {
        if (o.landmarkFiles.size() != 2)
            throw UsageError("--landmarks takes two files (source and target points) once");
        const PointTable a = PointTable::read(o.landmarkFiles[0], D);
        const PointTable b = PointTable::read(o.landmarkFiles[1], D);
        if (a.size() != b.size()) {
            OPENVDB_THROW(openvdb::ValueError, "--landmarks: " << o.landmarkFiles[0] << " has "
                                                               << a.size() << " points but "
                                                               << o.landmarkFiles[1] << " has "
                                                               << b.size());
        }
        if (a.size() == 0) {
            OPENVDB_THROW(openvdb::ValueError,
                          "--landmarks: " << o.landmarkFiles[0] << " has no points");
        }
        opts.sourceLandmarks = a.positions();
        opts.targetLandmarks = b.positions();
    }
    opts.landmarkWeight = o.landmarkWeight;
    if (o.autoLandmarks) opts.autoLandmarks = *o.autoLandmarks;
    opts.autoLandmarkLevels = o.autoLandmarkLevels;
    opts.autoLandmarkMinMotion = o.autoLandmarkMinMotion;
    if (o.autoAnchors) opts.autoAnchors = *o.autoAnchors;
    if (o.landmarkAnchors) opts.landmarkAnchors = *o.landmarkAnchors;
    if (o.anchorWeight) opts.anchorWeight = *o.anchorWeight;
    if (o.innerDistanceWeight) opts.innerDistanceWeight = *o.innerDistanceWeight;
    if (o.rigidLimbWeight) opts.rigidLimbWeight = *o.rigidLimbWeight;
    {
        const RigidLimbOptions byDimension = opts.rigidLimbOptions; // the preset's segments
        opts.rigidLimbOptions = o.rigidLimbOptions;
        if (!o.rigidSegmentGiven) {
            opts.rigidLimbOptions.segmentFrom = byDimension.segmentFrom;
            opts.rigidLimbOptions.segmentTo = byDimension.segmentTo;
        }
    }
    opts.rigidLimbMinMotion = o.rigidLimbMinMotion;
    if (o.rigidLimbAnchorRadius) opts.rigidLimbAnchorRadius = *o.rigidLimbAnchorRadius;
    opts.innerDistanceTolerance = o.innerDistanceTolerance;
    opts.innerDistanceRatio = o.innerDistanceRatio;
    opts.innerDistanceLevel = o.innerDistanceLevel;
    opts.innerDistanceLevels = o.innerDistanceLevels;
    if (o.secondPath) opts.secondPath = *o.secondPath;
    opts.secondPathShare = o.secondPathShare;
    opts.secondPathTarget = o.secondPathTarget;
    const std::size_t anchorCount = opts.anchorOptions.count; // the dimension's default
    opts.anchorOptions = o.anchorOptions;
    opts.anchorOptions.count = o.anchorCount.value_or(anchorCount);
    if (o.anchorNoiseTolerance) opts.anchorNoiseFactor = *o.anchorNoiseTolerance;
    opts.validate();
    if (o.deformationLevel < 0 || o.deformationLevel > opts.multiscale.maxLevel) {
        OPENVDB_THROW(openvdb::ValueError, "--deformation-level must be in [1, "
                                               << opts.multiscale.maxLevel << "], got "
                                               << o.deformationLevel);
    }

    const Surface<D>& source = surfaceOf<D>(in[0]);
    const Surface<D>& target = surfaceOf<D>(in[1]);
    // On stderr, also with --quiet, before the run: a small piece changes the result.
    for (const std::string& w :
         {smallPiecesWarning(in[0], "source"), smallPiecesWarning(in[1], "target")})
        if (!w.empty()) err << "vdb_match: warning: " << w << "\n";
    const UnitBoxPlacement placement = placeInUnitBox(source, target, opts.margin);
    // The grids written in world units (deformation, inverse, Jacobian; deformed.vdb of mesh
    // inputs) have voxels of 2^-level / scale: OpenVDB cannot represent them below its limit.
    const double worldSpacing = placement.toWorldLength(std::ldexp(1.0, -opts.multiscale.maxLevel));
    if (!(worldSpacing > MIN_WORLD_VOXEL_SIZE)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "the shapes are too small in world units: the finest spacing, "
                          << worldSpacing << " at level " << opts.multiscale.maxLevel
                          << ", is not above " << MIN_WORLD_VOXEL_SIZE
                          << ", the smallest voxel OpenVDB's transforms represent; rescale the "
                             "inputs (e.g. to millimetres) or lower --max-level");
    }

    // --init: an earlier result of these inputs; the run starts after its finest level (or at
    // the last requested one). --warm-start: another pair's map, carried through world space;
    // the run starts at --warm-start-level. Either way the cells stay no coarser than those of
    // the requested first level.
    const bool warm = !o.warmStart.empty();
    const std::string& initPath = warm ? o.warmStart : o.init;
    std::optional<InitialDeformation> init;
    if (!initPath.empty()) {
        if (!o.quiet) err << PROGRAM << ": reading " << initPath << std::endl;
        init = readInitialDeformation(initPath, placement, D,
                                      warm ? InitPlacement::Carried : InitPlacement::Same);
        const int firstRequested = opts.multiscale.minLevel;
        const int lastRequested = opts.multiscale.maxLevel;
        const int startLevel =
            !warm ? std::max(firstRequested, std::min(init->nextLevel(), lastRequested))
            : o.warmStartLevel
                ? *o.warmStartLevel
                : std::max(firstRequested, std::min(DEFAULT_WARM_START_LEVEL, lastRequested - 1));
        if (startLevel < firstRequested || startLevel > lastRequested) {
            throw UsageError("--warm-start-level " + std::to_string(startLevel) +
                             " is outside the levels " + std::to_string(firstRequested) + ".." +
                             std::to_string(lastRequested));
        }
        opts.coarsestLevel = firstRequested;
        opts.multiscale.minLevel = startLevel;
        opts.initial = init->start;
        opts.validate(D);
        checkInterrupted();
    }

    // The output directory must be usable before hours of work.
    namespace fs = std::filesystem;
    createOutputDirectory(o.outDir);
    // One match per output directory: a second run into it would interleave the outputs.
    const OutputLock lock(o.outDir);

    int firstSurfaceLevel = opts.multiscale.maxLevel + 1; // none
    if (opts.multiscale.surfaceTolerance > 0) {
        for (int l = opts.multiscale.maxLevel; l >= opts.multiscale.minLevel; --l)
            if (opts.multiscale.surfaceTestAt(l)) firstSurfaceLevel = l;
    }
    auto progress = std::make_unique<ProgressPrinter>(err, o, D, opts.multiscale.minLevel,
                                                      opts.multiscale.maxLevel, firstSurfaceLevel);
    progress->message(
        "matching " + in[0].path + " -> " + in[1].path + " (" + std::to_string(D) + "D, " +
        (o.preset == "paper" ? "preset paper, " : "") + toString(opts.multiscale.kind) +
        " energy, levels " + std::to_string(opts.multiscale.minLevel) + ".." +
        std::to_string(opts.multiscale.maxLevel) +
        (!init  ? std::string()
         : warm ? ", warm start from " + o.warmStart
                : ", from " + o.init + " (levels " + std::to_string(init->firstLevel) + ".." +
                      std::to_string(init->finestLevel) +
                      (init->interrupted ? ", interrupted" : "") + ")") +
        ")");
    MatchObserver observer;
    observer.levelStart = [&](const LevelSummary& s) {
        progress->levelStart(s.level, s.lattice, s.fieldSeconds, s.latticeSeconds);
    };
    observer.iteration = [&](const solver::IterationInfo& i) { progress->iteration(i); };
    observer.levelEnd = [&](const LevelSummary& s) { progress->levelEnd(s); };
    observer.autoLandmarks = [&](const AutoLandmarkSummary& a) {
        progress->message(
            autoLandmarkLine(a, opts.multiscale.minLevel, opts.anchorOptions.tolerance));
    };
    observer.innerDistance = [&](const InnerDistanceSummary& f) {
        progress->message(innerDistanceStartLine(f));
    };
    observer.secondPath = [&](const SecondPathSummary& sp) {
        progress->message(secondPathLine(sp));
    };

    SignalInterrupter interrupter;
    // A start that folds on the new lattice: --init, an earlier result of the same pair, is
    // refused (a finer result sampled on coarser cells); a warm start (another pair's map:
    // possible where the shapes moved much) falls back to the identity at the requested levels.
    std::string warmFallback;
    const MatchResult<D> result = [&]() {
        try {
            return match<D>(source, target, placement, opts, observer, &interrupter);
        } catch (const InitialDeformationFolds& e) {
            if (!warm) {
                OPENVDB_THROW(openvdb::ValueError,
                              oneLine(e.what()) << "; start from a result whose finest level is "
                                                   "below the first level of this run");
            }
            warmFallback = oneLine(e.what());
            opts.multiscale.minLevel = opts.coarsestLevel;
            opts.coarsestLevel = 0;
            opts.initial.reset();
            progress = std::make_unique<ProgressPrinter>(
                err, o, D, opts.multiscale.minLevel, opts.multiscale.maxLevel, firstSurfaceLevel);
            progress->message("the warm start folds on the first lattice (" + warmFallback +
                              "); starting from the identity at levels " +
                              std::to_string(opts.multiscale.minLevel) + ".." +
                              std::to_string(opts.multiscale.maxLevel));
            return match<D>(source, target, placement, opts, observer, &interrupter);
        }
    }();
    const bool interrupted = result.isInterrupted() || wasSignalled();
    if (!result.lattice) {
        // Stopped before the first level had a lattice: nothing to write.
        throw Interrupted{};
    }

    // Everything is computed in memory first, then written file by file (each atomically).
    const Clock::time_point writeStart = Clock::now();
    progress->message("writing " + o.outDir);
    const solver::Report& last = result.levels.back().report;
    openvdb::Vec3SGrid::Ptr deformation =
        makeDeformationGrid<D>(*result.lattice, result.displacement, placement, o.deformationLevel);
    deformation->insertMeta("vdbmatch_version", openvdb::StringMetadata(VDBMATCH_VERSION));
    deformation->insertMeta("vdbmatch_command", openvdb::StringMetadata(o.commandLine));
    deformation->insertMeta("vdbmatch_energy",
                            openvdb::StringMetadata(toString(opts.multiscale.kind)));
    deformation->insertMeta(
        "vdbmatch_levels",
        openvdb::StringMetadata(
            std::to_string(opts.coarsestLevel > 0 ? opts.coarsestLevel : opts.multiscale.minLevel) +
            ".." + std::to_string(result.lattice->level())));
    if (init && warmFallback.empty()) {
        deformation->insertMeta(warm ? "vdbmatch_warm_start" : "vdbmatch_init",
                                openvdb::StringMetadata(initPath));
    }
    deformation->insertMeta("vdbmatch_c_match", openvdb::DoubleMetadata(p.cMatch));
    deformation->insertMeta("vdbmatch_c_mem", openvdb::DoubleMetadata(p.cMem));
    deformation->insertMeta("vdbmatch_coarse_membrane_factor",
                            openvdb::DoubleMetadata(opts.multiscale.coarseMembraneFactor));
    deformation->insertMeta("vdbmatch_membrane_saturation",
                            openvdb::DoubleMetadata(p.membraneSaturation));
    deformation->insertMeta(
        "vdbmatch_membrane_saturation_levels",
        openvdb::Int32Metadata(static_cast<int32_t>(opts.multiscale.membraneSaturationLevels)));
    deformation->insertMeta("vdbmatch_c_bend", openvdb::DoubleMetadata(p.cBend));
    deformation->insertMeta("vdbmatch_c_vol", openvdb::DoubleMetadata(p.cVol));
    deformation->insertMeta("vdbmatch_coarse_volume_factor",
                            openvdb::DoubleMetadata(opts.multiscale.coarseVolumeFactor));
    deformation->insertMeta("vdbmatch_coarse_sigma_factor",
                            openvdb::DoubleMetadata(opts.multiscale.coarseSigmaFactor));
    deformation->insertMeta("vdbmatch_q", openvdb::DoubleMetadata(p.q));
    deformation->insertMeta("vdbmatch_theta", openvdb::DoubleMetadata(p.theta));
    deformation->insertMeta("vdbmatch_tau", openvdb::DoubleMetadata(p.tau));
    deformation->insertMeta("vdbmatch_margin", openvdb::DoubleMetadata(opts.margin));
    deformation->insertMeta("vdbmatch_energy_total", openvdb::DoubleMetadata(last.energy));
    deformation->insertMeta("vdbmatch_energy_match",
                            openvdb::DoubleMetadata(last.terms.match[0] + last.terms.match[1]));
    deformation->insertMeta("vdbmatch_energy_mem",
                            openvdb::DoubleMetadata(last.terms.mem[0] + last.terms.mem[1]));
    deformation->insertMeta("vdbmatch_energy_bend",
                            openvdb::DoubleMetadata(last.terms.bend[0] + last.terms.bend[1]));
    deformation->insertMeta("vdbmatch_energy_vol",
                            openvdb::DoubleMetadata(last.terms.vol[0] + last.terms.vol[1]));
    deformation->insertMeta("vdbmatch_residual_mean",
                            openvdb::DoubleMetadata(result.residual.meanWorld));
    deformation->insertMeta("vdbmatch_residual_max",
                            openvdb::DoubleMetadata(result.residual.maxWorld));
    deformation->insertMeta("vdbmatch_min_jacobian", openvdb::DoubleMetadata(result.minJacobian));
    deformation->insertMeta("is_interrupted", openvdb::BoolMetadata(interrupted));

    // The deformed shape as a level set, on the source's grid when it came as one.
    openvdb::math::Transform::Ptr xform = in[0].transform;
    if (!xform) {
        const double voxel = placement.toWorldLength(std::ldexp(1.0, -result.lattice->level()));
        xform = openvdb::math::Transform::createLinearTransform(voxel);
    }
    openvdb::FloatGrid::Ptr deformed = levelSetFromSurface<D>(result.deformedSource, *xform, 3.0);
    deformed->setName("surface");
    deformed->setGridClass(openvdb::GRID_LEVEL_SET);
    deformed->insertMeta("vdbmatch_version", openvdb::StringMetadata(VDBMATCH_VERSION));
    deformed->insertMeta("vdbmatch_command", openvdb::StringMetadata(o.commandLine));
    deformed->insertMeta("is_interrupted", openvdb::BoolMetadata(interrupted));

    ExtraOutputs extra;
    // --half: half floats keep 11 significant bits of each displacement, which at fine levels
    // can flip a thin simplex. A grid is stored in half only if its rounded values keep every
    // det D > 0; otherwise it stays float and the report says so.
    auto chooseHalf = [&](const openvdb::Vec3SGrid::Ptr& grid, const char* file) {
        if (!o.half || !grid) return;
        const double minDet = minDeterminantAsHalf(*grid);
        if (minDet > 0) {
            grid->setSaveFloatAsHalf(true);
        } else {
            progress->message(std::string("warning: --half would fold ") + file + " (min det D " +
                              fixed("%.3g", minDet) + " after rounding): written in float");
            extra.halfRefused.push_back(file);
        }
    };
    chooseHalf(deformation, "deformation.vdb");

    // det D phi per cell first: the one output that can fail (--log-jacobian of a fold), so
    // that it fails before any file is written.
    openvdb::FloatGrid::Ptr jacobianGrid;
    if (!interrupted && o.writeJacobian && !wasSignalled()) {
        const Clock::time_point t0 = Clock::now();
        jacobianGrid =
            makeJacobianGrid(DeformationField(deformation), o.logJacobian, true, &interrupter);
        if (jacobianGrid) {
            extra.jacobian = true;
            extra.jacobianSeconds = secondsSince(t0);
            extra.detMin = jacobianGrid->metaValue<double>("vdbmatch_det_min");
            extra.detMax = jacobianGrid->metaValue<double>("vdbmatch_det_max");
            jacobianGrid->insertMeta("vdbmatch_version", openvdb::StringMetadata(VDBMATCH_VERSION));
            jacobianGrid->insertMeta("vdbmatch_command", openvdb::StringMetadata(o.commandLine));
        }
    }
    const std::string dir = o.outDir;
    openvdb::MetaMap fileMeta;
    fileMeta.insertMeta("creator",
                        openvdb::StringMetadata(std::string("vdbmatch ") + VDBMATCH_VERSION));
    // A stale inverse or Jacobian of an earlier run must not sit next to this deformation.
    for (const char* name : {"inverse.vdb", "jacobian.vdb"}) {
        std::error_code removeError; // absent is fine
        fs::remove(fs::path(dir) / name, removeError);
    }
    // Each file is compressed and written on one thread (OpenVDB's blosc calls are serial), so
    // the files are written side by side, each one atomically, and while the exact inverse is
    // computed (which only reads the deformation grid). wait() rethrows the first writer's
    // exception, after the others finished.
    tbb::task_group writers;
    writers.run([&] {
        writeGridsAtomically((fs::path(dir) / "deformation.vdb").string(), {deformation}, fileMeta);
    });
    if (jacobianGrid) {
        writers.run([&] {
            writeGridsAtomically((fs::path(dir) / "jacobian.vdb").string(), {jacobianGrid},
                                 fileMeta);
        });
    }
    writers.run([&] {
        writeGridsAtomically((fs::path(dir) / "deformed.vdb").string(), {deformed}, fileMeta);
        writeFileAtomically((fs::path(dir) / "deformed.obj").string(),
                            [&](std::ostream& os) { writeObj(os, result.deformedSource); });
    });

    // The exact inverse at every node, from the grid as written.
    openvdb::Vec3SGrid::Ptr inverseGrid;
    try {
        if (!interrupted && o.writeInverse && !wasSignalled()) {
            progress->message("computing the exact inverse at " +
                              std::to_string(deformation->activeVoxelCount()) + " nodes");
            const Clock::time_point t0 = Clock::now();
            const InverseGridResult inv =
                makeInverseGrid(DeformationField(deformation), true, &interrupter);
            if (inv.grid) {
                inverseGrid = inv.grid;
                extra.inverse = true;
                extra.inverseNodes = inv.nodes;
                extra.inverseFailures = inv.failures;
                extra.inverseMaxResidual = inv.maxResidual;
                extra.inverseSeconds = secondsSince(t0);
                inverseGrid->removeMeta("vdbmatch_inverse_max_residual");
                inverseGrid->insertMeta("vdbmatch_inverse_max_residual",
                                        openvdb::DoubleMetadata(inv.maxResidual));
                if (inv.failures) {
                    progress->message("warning: the inverse walk failed at " +
                                      std::to_string(inv.failures) +
                                      " nodes (det D phi <= 0); inverse.vdb is wrong there");
                }
                chooseHalf(inverseGrid, "inverse.vdb");
                writers.run([&] {
                    writeGridsAtomically((fs::path(dir) / "inverse.vdb").string(), {inverseGrid},
                                         fileMeta);
                });
            }
        }
    } catch (...) {
        writers.wait(); // no writer may outlive the grids it writes
        throw;
    }
    writers.wait();
    extra.files.push_back("deformation.vdb");
    if (inverseGrid) extra.files.push_back("inverse.vdb");
    if (jacobianGrid) extra.files.push_back("jacobian.vdb");
    extra.files.insert(extra.files.end(), {"deformed.vdb", "deformed.obj", "report.json"});
    const bool converged = last.status == solver::Status::Converged;
    const std::string status = interrupted ? "interrupted"
                               : converged ? "converged"
                                           : "not converged";
    const double writeSeconds = secondsSince(writeStart);
    const std::string report = reportJson<D>(o, opts, in, result, status, writeSeconds, extra,
                                             init ? &*init : nullptr, warmFallback);
    writeFileAtomically((fs::path(dir) / "report.json").string(),
                        [&](std::ostream& os) { os << report; });

    out << "vdb_match: " << status << "; energy " << fixed("%.6e", last.energy)
        << ", residual mean " << fixed("%.3e", result.residual.meanWorld) << " max "
        << fixed("%.3e", result.residual.maxWorld) << " (world units; "
        << fixed("%.2e", result.residual.meanUnit) << " of the unit box, h/2 = "
        << fixed("%.2e", 0.5 * std::ldexp(1.0, -result.lattice->level())) << "), min det "
        << fixed("%.3g", result.minJacobian) << ", " << duration(secondsSince(start)) << "\n";
    out << "vdb_match: " << targetResidualLine(result.targetResidual, in[1]) << "\n";
    if (result.targetResidual.farShare > TARGET_RESIDUAL_WARNING_SHARE) {
        // On stderr, also with --quiet: it is about the result, not progress.
        err << "vdb_match: warning: " << fixed("%.1f", 100 * result.targetResidual.farShare)
            << "% of M2 is farther than sigma from phi(M1): the deformed source does not reach "
               "that part of the target (compare deformed.obj with it"
            << (opts.secondPath && !opts.secondPathTarget
                    ? "; --second-path-target on runs the levels again when this happens"
                    : "")
            << ")\n";
    }
    if (result.autoLandmarks.requested)
        out << "vdb_match: "
            << autoLandmarkLine(result.autoLandmarks, opts.multiscale.minLevel,
                                opts.anchorOptions.tolerance)
            << "\n";
    if (result.innerDistance.requested)
        out << "vdb_match: " << innerDistanceLine(result.innerDistance) << "\n";
    if (opts.hessianNoiseFactor > 0) out << "vdb_match: " << noiseLine(result, opts) << "\n";
    if (result.secondPath.ran) out << "vdb_match: " << secondPathLine(result.secondPath) << "\n";
    out << "vdb_match: wrote " << (fs::path(dir) / "deformation.vdb").string();
    for (std::size_t i = 1; i < extra.files.size(); ++i)
        out << ", " << extra.files[i];
    out << "\n";
    out.flush();
    if (interrupted) return EXIT_INTERRUPTED;
    if (o.strict && !converged) return EXIT_NOT_CONVERGED;
    return EXIT_OK;
}

} // namespace

std::string
matchOptionHelp()
{
    return optionHelp(matchOptionTable());
}

std::vector<OptionDescription>
matchOptionDescriptions()
{
    return describeOptions(matchOptionTable());
}

int
runMatchCommand(int argc, const char* const* argv, int first, std::ostream& out, std::ostream& err)
{
    const MatchCliOptions o = parseMatchOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    auto say = [&](const std::string& text) {
        if (!o.quiet) err << PROGRAM << ": " << text << std::endl;
    };
    Shape in[2];
    say("reading " + o.source);
    in[0] = readInputShape(o.source, o.grid.empty() ? o.sourceGrid : o.grid, o.isoValue);
    checkInterrupted();
    say("reading " + o.target);
    in[1] = readInputShape(o.target, o.grid.empty() ? o.targetGrid : o.grid, o.isoValue);
    checkInterrupted();
    if (in[0].dim != in[1].dim) {
        OPENVDB_THROW(openvdb::ValueError, "'" << o.source << "' is a " << in[0].dim
                                               << "D shape but '" << o.target << "' is "
                                               << in[1].dim << "D");
    }
    return in[0].dim == 2 ? runMatch<2>(o, in, out, err) : runMatch<3>(o, in, out, err);
}

} // namespace cli
} // namespace vdbmatch
