/// @file EnergyCommand.cc
/// @brief `vdb_match energy`: the terms of the matching energy of phi = Id (docs/cli.md), for
///        the same inputs as `match` (level sets, 2D slices, meshes, polylines), read, placed and
///        turned into distance fields exactly as `match` does at its first level.
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/geometry/SurfaceNoise.h>
#include <vdbmatch/io/ShapeIO.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <array>
#include <functional>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

EnergyParameters
EnergyOptions::parameters(int dim) const
{
    EnergyParameters p = EnergyParameters::defaults(dim);
    if (cMatch) p.cMatch = *cMatch;
    if (cMem) p.cMem = *cMem;
    if (cBend) p.cBend = *cBend;
    if (cVol) p.cVol = *cVol;
    if (q) p.q = *q;
    if (theta) p.theta = *theta;
    p.tau = tau;
    p.membraneSaturation = membraneSaturation;
    return p;
}

double
EnergyOptions::latticeNoiseFactor(int dim) const
{
    return latticeNoiseSmoothing ? *latticeNoiseSmoothing
                                 : (dim == 3 ? LATTICE_NOISE_SMOOTHING_FACTOR_3D : 0.0);
}

namespace {

/// Finest --level of `energy`: its lattice is dense (6 * 8^8 = 100 M simplices at 8 in 3D,
/// 2 * 4^11 = 8 M at 11 in 2D).
constexpr int MAX_ENERGY_LEVEL_3D = 8;
constexpr int MAX_ENERGY_LEVEL_2D = 11;

/// The options of `energy`, in help order; help strings show the defaults.
std::vector<Option<EnergyOptions>>
energyOptionTable()
{
    const EnergyOptions d;
    const EnergyParameters p3 = EnergyParameters::defaults(3), p2 = EnergyParameters::defaults(2);
    auto both = [](double a3, double a2) {
        return formatNumber(a3) + " in 3D, " + formatNumber(a2) + " in 2D";
    };
    using O = EnergyOptions;
    // clang-format off
    return {
        {"--source", "FILE", "Input",
         "the source shape M1, instead of the first positional argument",
         [](O& o, const std::string& v) { o.source = v; }},
        {"--target", "FILE", "Input",
         "the target shape M2, instead of the second positional argument",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--grid", "NAME", "Input",
         "grid to read from .vdb inputs (default: the only float grid of each file)",
         [](O& o, const std::string& v) { o.grid = v; }},
        {"--source-grid", "NAME", "Input", "grid to read from SOURCE (not with --grid)",
         [](O& o, const std::string& v) { o.sourceGrid = v; }},
        {"--target-grid", "NAME", "Input", "grid to read from TARGET (not with --grid)",
         [](O& o, const std::string& v) { o.targetGrid = v; }},
        {"--iso-value", "X", "Input",
         "read .vdb fog volumes (densities) as the level set of their iso-surface at density X, "
         "inside where the density exceeds X (default: densities are refused)",
         [](O& o, const std::string& v) { o.isoValue = parseDouble("--iso-value", v); }},
        {"--level", "L", "Domain and resolution",
         "lattice level: h = 2^-L in the unit box, 1.." + std::to_string(MAX_ENERGY_LEVEL_3D) +
             " in 3D, 1.." + std::to_string(MAX_ENERGY_LEVEL_2D) + " in 2D (default " +
             std::to_string(d.level) + ")",
         [](O& o, const std::string& v) { o.level = parseInt("--level", v); }},
        {"--margin", "X", "Domain and resolution",
         "space left on each side of the shapes' common bounding box in the unit box, "
         "[0, 0.5) (default " + formatNumber(d.margin) + ")",
         [](O& o, const std::string& v) { o.margin = parseDouble("--margin", v); }},
        {"--energy", "KIND", "Energy (paper tab:parameters)",
         "symmetric (eq:Esym) or directional (eq:Ecomparison) (default " +
             toString(d.kind) + ")",
         [](O& o, const std::string& v) {
             if (v != "symmetric" && v != "directional") {
                 throw UsageError("--energy expects 'symmetric' or 'directional', got '" + v +
                                  "'");
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
        {"--c-bend", "X", "Energy (paper tab:parameters)",
         "weight of the bending term (default " + both(p3.cBend, p2.cBend) + ")" +
             "\npaper: c_bend, eq:EsymBend",
         [](O& o, const std::string& v) { o.cBend = parseDouble("--c-bend", v); }},
        {"--c-vol", "X", "Energy (paper tab:parameters)",
         "weight of the volume term, times sigma^theta (default " + both(p3.cVol, p2.cVol) + ")" +
             "\npaper: c_vol, eq:EsymVol",
         [](O& o, const std::string& v) { o.cVol = parseDouble("--c-vol", v); }},
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
        {"--membrane-saturation", "X", "Energy (paper tab:parameters)",
         "an addition to the paper: take both membrane densities through s log(1 + W/s), >= 0 "
         "(default 0: the paper's W; match's default acts at its first levels only)",
         [](O& o, const std::string& v) {
             o.membraneSaturation = parseDouble("--membrane-saturation", v);
         }},
        {"--hessian-smoothing", "N", "Energy (paper tab:parameters)",
         "[1,2,1]/4 smoothing passes of the distance Hessian, >= 0 (default " +
             std::to_string(d.hessianSmoothing) + ")",
         [](O& o, const std::string& v) {
             o.hessianSmoothing = parseInt("--hessian-smoothing", v);
         }},
        {"--noise-smoothing", "F", "Energy (paper tab:parameters)",
         "an addition to the paper: smooth each shape's distance Hessian over F times its own "
         "vertex noise, as match does, >= 0 (default " +
             formatNumber(d.noiseSmoothing) + "; match's default is " +
             formatNumber(NOISE_SMOOTHING_LENGTH_FACTOR) + ")",
         [](O& o, const std::string& v) { o.noiseSmoothing = parseDouble("--noise-smoothing", v); }},
        {"--lattice-noise-smoothing", "G", "Energy (paper tab:parameters)",
         "an addition to the paper: with --noise-smoothing, smooth each shape's Hessian over at "
         "least G times the noise a lattice of h = 1/128 sees on it, as match does, >= 0, 0: "
         "off (default " +
             formatNumber(LATTICE_NOISE_SMOOTHING_FACTOR_3D) + " in 3D, 0 in 2D, as match's)",
         [](O& o, const std::string& v) {
             o.latticeNoiseSmoothing = parseDouble("--lattice-noise-smoothing", v);
         }},
        {"--noise-bending", "X", "Energy (paper tab:parameters)",
         "an addition to the paper: with --noise-smoothing, weigh the bending term by c_bend / "
         "(1 + n/X) for the larger number n of noise smoothing passes of the two shapes at "
         "--level, as match does, >= 0, 0: off (default " +
             formatNumber(d.noiseBending) + ", as match's)",
         [](O& o, const std::string& v) { o.noiseBending = parseDouble("--noise-bending", v); }},
        {"--json", nullptr, "Output", "print the results as one JSON object",
         [](O& o, const std::string&) { o.json = true; }},
        {"--quiet", nullptr, "Output", "no progress messages on stderr (errors are still printed)",
         [](O& o, const std::string&) { o.quiet = true; }},
        {"--threads", "N", "Execution", "number of threads, 0 = all cores (default 0)",
         [](O& o, const std::string& v) { o.threads = parseThreads(v); }},
    };
    // clang-format on
}

////////////////////////////////////////////////////////////////////////////////
// The energy command

struct Timings
{
    double read = 0, place = 0, fields = 0, lattice = 0, energy = 0, total = 0;
};

/// What was evaluated, for the outputs.
struct EnergyReport
{
    int dim = 3;
    EnergyParameters params;
    UnitBoxPlacement placement;
    double h = 0, sigma = 0;
    std::size_t simplices = 0;
    EnergyTerms terms;
    double total = 0;
    std::array<NoiseReading, 2> noise; ///< readNoise() of the placed shapes
    double bendingFactor = 1;          ///< noiseBendingFactor() at the level
    Timings time;
};

std::size_t
vertexCount(const Shape& s)
{
    return s.dim == 2 ? s.curve.points.size() : s.surface.points.size();
}

std::size_t
elementCount(const Shape& s)
{
    return s.dim == 2 ? s.curve.elements.size() : s.surface.elements.size();
}

void
printHuman(std::ostream& out, const EnergyOptions& o, const Shape (&in)[2], const EnergyReport& r)
{
    out << "vdb_match energy: " << toString(o.kind) << " energy of phi = Id, " << r.dim
        << "D, level " << o.level << "\n";
    const char* roles[2] = {"source", "target"};
    for (int i = 0; i < 2; ++i) {
        out << "  " << roles[i] << ":  " << in[i].path << ", " << in[i].format
            << (in[i].grid.empty() ? std::string() : " '" + in[i].grid + "'") << ", "
            << vertexCount(in[i]) << " vertices, " << elementCount(in[i])
            << (r.dim == 2 ? " segments\n" : " triangles\n");
    }
    out << "  placement: unit = " << r.placement.scale << " * (world - " << r.placement.worldOrigin
        << "), margin " << r.placement.margin << "\n";
    out << "  h = " << r.h << ", sigma = " << r.sigma << ", simplices " << r.simplices
        << ", band simplices " << r.terms.bandSimplices << ", inverted "
        << r.terms.invertedSimplices << "\n";
    out << "  term         direct          inverse         sum\n";
    const char* names[4] = {"match", "mem", "bend", "vol"};
    const Real* halves[4] = {r.terms.match, r.terms.mem, r.terms.bend, r.terms.vol};
    for (int k = 0; k < 4; ++k) {
        out << "  " << names[k] << std::string(7 - std::string(names[k]).size(), ' ')
            << fixed("%15.8e", halves[k][0]) << " " << fixed("%15.8e", halves[k][1]) << " "
            << fixed("%15.8e", halves[k][0] + halves[k][1]) << "\n";
    }
    out << "  total  " << fixed("%15.8e", r.total) << "\n";
    const Timings& t = r.time;
    out << "  time [s]: read " << fixed("%.3f", t.read) << ", place " << fixed("%.3f", t.place)
        << ", fields " << fixed("%.3f", t.fields) << ", lattice " << fixed("%.3f", t.lattice)
        << ", energy " << fixed("%.3f", t.energy) << ", total " << fixed("%.3f", t.total) << "\n";
}

void
printJson(std::ostream& out, const EnergyOptions& o, const Shape (&in)[2], const EnergyReport& r)
{
    auto pair = [](const Real* v) { return Json::array({v[0], v[1]}); };
    Json j;
    j["command"] = "energy";
    j["version"] = VDBMATCH_VERSION;
    j["energy"] = toString(o.kind);
    j["dimension"] = r.dim;
    j["source"] = shapeJson(in[0]);
    j["target"] = shapeJson(in[1]);
    j["placement"] = Json{{"worldOrigin", jsonVec(r.placement.worldOrigin)},
                          {"scale", r.placement.scale},
                          {"margin", r.placement.margin}};
    j["parameters"] = energyParametersJson(r.params);
    j["parameters"]["hessianSmoothing"] = o.hessianSmoothing;
    j["parameters"]["noiseSmoothing"] = o.noiseSmoothing;
    j["parameters"]["latticeNoiseSmoothing"] = o.latticeNoiseFactor(r.dim);
    j["parameters"]["noiseBending"] = o.noiseBending;
    j["bendingFactor"] = r.bendingFactor;
    if (o.noiseSmoothing > 0) {
        j["noise"] = Json{{"source", r.noise[0].vertex},
                          {"target", r.noise[1].vertex},
                          {"lattice", {r.noise[0].lattice, r.noise[1].lattice}},
                          {"smoothingLength", {r.noise[0].length, r.noise[1].length}}};
    }
    j["level"] = o.level;
    j["h"] = r.h;
    j["sigma"] = r.sigma;
    j["simplices"] = r.simplices;
    j["bandSimplices"] = r.terms.bandSimplices;
    j["invertedSimplices"] = r.terms.invertedSimplices;
    j["terms"] = Json{{"match", pair(r.terms.match)},
                      {"mem", pair(r.terms.mem)},
                      {"bend", pair(r.terms.bend)},
                      {"vol", pair(r.terms.vol)}};
    j["total"] = r.total;
    const Timings& t = r.time;
    j["timings"] = Json{{"read", t.read},       {"place", t.place},   {"fields", t.fields},
                        {"lattice", t.lattice}, {"energy", t.energy}, {"total", t.total}};
    out << dumpJson(j);
}

/// Places, builds the distance fields at the level (buildShapeSampler, as match) and evaluates
/// the energy of phi = Id on the dense lattice.
template <int D>
void
evaluate(const EnergyOptions& o, const Shape (&in)[2], EnergyReport& r,
         const std::function<void(const std::string&)>& progress,
         openvdb::util::NullInterrupter* interrupter)
{
    Clock::time_point t0 = Clock::now();
    const Surface<D>& source = in[0].get<D>();
    const Surface<D>& target = in[1].get<D>();
    r.placement = placeInUnitBox<D>(source, target, o.margin);
    Surface<D> unit[2] = {source, target};
    for (Surface<D>& s : unit) {
        for (Vec<D>& p : s.points) {
            openvdb::Vec3d w(0.0);
            for (int a = 0; a < D; ++a)
                w[a] = p[a];
            const openvdb::Vec3d u = r.placement.toUnit(w);
            for (int a = 0; a < D; ++a) {
                if (!(u[a] > 0 && u[a] < 1)) {
                    OPENVDB_THROW(openvdb::ValueError,
                                  "energy: a shape does not fit in the unit box with this "
                                  "placement (a vertex maps outside (0,1)^d)");
                }
                p[a] = u[a];
            }
        }
    }
    r.time.place = secondsSince(t0);

    t0 = Clock::now();
    progress("computing the distance fields at level " + std::to_string(o.level));
    ShapeSamplerOptions samplerOptions;
    samplerOptions.fields.tau = r.params.tau;
    samplerOptions.fields.hessianSmoothing = o.hessianSmoothing;
    ShapeSamplerOptions sampler1 = samplerOptions, sampler2 = samplerOptions;
    for (int s = 0; s < 2; ++s)
        r.noise[size_t(s)] = readNoise(unit[s], o.noiseSmoothing, o.latticeNoiseFactor(D));
    sampler1.fields.hessianSmoothingLength = r.noise[0].length;
    sampler2.fields.hessianSmoothingLength = r.noise[1].length;
    const typename FieldSampler<D>::ConstPtr shape1 =
        buildShapeSampler<D>(unit[0], o.level, sampler1);
    checkInterrupted();
    const typename FieldSampler<D>::ConstPtr shape2 =
        buildShapeSampler<D>(unit[1], o.level, sampler2);
    checkInterrupted();
    r.time.fields = secondsSince(t0);

    t0 = Clock::now();
    const SimplexLattice<D> lattice = SimplexLattice<D>::dense(o.level);
    r.time.lattice = secondsSince(t0);
    checkInterrupted();
    t0 = Clock::now();
    progress("evaluating the energy");
    r.bendingFactor =
        noiseBendingFactor(pairSmoothingPasses(sampler1.fields.hessianSmoothingLength,
                                               sampler2.fields.hessianSmoothingLength, lattice.h()),
                           o.noiseBending);
    EnergyParameters levelParams = r.params;
    levelParams.cBend *= r.bendingFactor;
    const Energy<D> energy(lattice, *shape1, *shape2, levelParams, o.kind);
    const NodeVectors<D> u = NodeVectors<D>::Zero(D, Eigen::Index(lattice.nodeCount()));
    r.total = energy.value(u, &r.terms, /*threaded=*/true, interrupter);
    checkInterrupted();
    r.time.energy = secondsSince(t0);
    r.h = lattice.h();
    r.sigma = energy.sigma();
    r.simplices = lattice.simplexCount();
}

int
runEnergy(const EnergyOptions& o, std::ostream& out, std::ostream& err)
{
    const Clock::time_point start = Clock::now();
    EnergyReport r;
    auto progress = [&](const std::string& message) {
        if (!o.quiet) err << PROGRAM << ": " << message << std::endl;
    };
    if (!(o.noiseSmoothing >= 0) || !std::isfinite(o.noiseSmoothing)) {
        OPENVDB_THROW(openvdb::ValueError, "--noise-smoothing must be a finite number >= 0");
    }
    if (o.latticeNoiseSmoothing &&
        (!(*o.latticeNoiseSmoothing >= 0) || !std::isfinite(*o.latticeNoiseSmoothing))) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--lattice-noise-smoothing must be a finite number >= 0");
    }
    if (!(o.noiseBending >= 0) || !std::isfinite(o.noiseBending)) {
        OPENVDB_THROW(openvdb::ValueError, "--noise-bending must be a finite number >= 0");
    }
    if (o.hessianSmoothing < 0) {
        OPENVDB_THROW(openvdb::ValueError, "--hessian-smoothing must be >= 0, got " +
                                               std::to_string(o.hessianSmoothing));
    }
    // The level's range depends on the dimension, known once read; refuse what no dimension
    // accepts before reading.
    if (o.level < 1 || o.level > MAX_ENERGY_LEVEL_2D) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--level must be in [1, " + std::to_string(MAX_ENERGY_LEVEL_3D) +
                          "] in 3D, [1, " + std::to_string(MAX_ENERGY_LEVEL_2D) +
                          "] in 2D (energy evaluates a dense lattice), got " +
                          std::to_string(o.level));
    }
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    SignalInterrupter interrupter;

    // 1. Read, exactly as match does.
    Shape in[2];
    Clock::time_point t0 = Clock::now();
    const std::string paths[2] = {o.source, o.target};
    const std::string names[2] = {o.grid.empty() ? o.sourceGrid : o.grid,
                                  o.grid.empty() ? o.targetGrid : o.grid};
    for (int i = 0; i < 2; ++i) {
        progress("reading " + paths[i]);
        in[i] = readInputShape(paths[i], names[i], o.isoValue);
        checkInterrupted();
    }
    r.time.read = secondsSince(t0);
    if (in[0].dim != in[1].dim) {
        OPENVDB_THROW(openvdb::ValueError, "'" << o.source << "' is a " << in[0].dim
                                               << "D shape but '" << o.target << "' is "
                                               << in[1].dim << "D");
    }
    r.dim = in[0].dim;
    // As match: on stderr, also with --quiet (a small piece changes the energy).
    for (const std::string& w :
         {smallPiecesWarning(in[0], "source"), smallPiecesWarning(in[1], "target")})
        if (!w.empty()) err << PROGRAM << ": warning: " << w << "\n";
    if (r.dim == 3 && o.level > MAX_ENERGY_LEVEL_3D) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--level must be in [1, " + std::to_string(MAX_ENERGY_LEVEL_3D) +
                          "] in 3D (energy evaluates a dense lattice of 6 * 8^level "
                          "simplices), got " +
                          std::to_string(o.level));
    }
    r.params = o.parameters(r.dim);
    r.params.validate();

    // 2..4. Place, fields, energy.
    if (r.dim == 2) {
        evaluate<2>(o, in, r, progress, &interrupter);
    } else {
        evaluate<3>(o, in, r, progress, &interrupter);
    }
    r.time.total = secondsSince(start);

    if (o.json) {
        printJson(out, o, in, r);
    } else {
        printHuman(out, o, in, r);
    }
    out.flush();
    return EXIT_OK;
}

} // namespace

std::string
energyOptionHelp()
{
    return optionHelp(energyOptionTable());
}

std::vector<OptionDescription>
energyOptionDescriptions()
{
    return describeOptions(energyOptionTable());
}

EnergyOptions
parseEnergyOptions(int argc, const char* const* argv, int first)
{
    const std::vector<Option<EnergyOptions>> table = energyOptionTable();
    EnergyOptions o;
    const std::vector<std::string> positional = parseOptions(table, argc, argv, first, o);
    assignInputs(positional, o.source, o.target,
                 "energy expects SOURCE.vdb TARGET.vdb (or two other shapes that match reads)");
    if (!o.grid.empty() && (!o.sourceGrid.empty() || !o.targetGrid.empty())) {
        throw UsageError("--grid cannot be combined with --source-grid or --target-grid");
    }
    checkIsoValueInputs(o.isoValue, o.source, o.target);
    const std::string names[2] = {o.grid.empty() ? o.sourceGrid : o.grid,
                                  o.grid.empty() ? o.targetGrid : o.grid};
    const std::string paths[2] = {o.source, o.target};
    for (int i = 0; i < 2; ++i) {
        if (!names[i].empty() && isShapeFile(paths[i]) && !isLevelSetFile(paths[i])) {
            throw UsageError("--grid applies to .vdb inputs, not to '" + paths[i] + "'");
        }
    }
    return o;
}

int
runEnergyCommand(int argc, const char* const* argv, int first, std::ostream& out, std::ostream& err)
{
    const EnergyOptions options = parseEnergyOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    return runEnergy(options, out, err);
}

} // namespace cli
} // namespace vdbmatch
