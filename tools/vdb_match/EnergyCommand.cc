/// @file EnergyCommand.cc
/// @brief `vdb_match energy`: the terms of the matching energy of phi = Id (docs/cli.md).
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

/// Finest --level of `energy`: its lattice is dense (8^8 cells = 100 M simplices at 8).
constexpr int MAX_ENERGY_LEVEL = 8;

/// The options of `energy`, in help order; help strings show the defaults of @a d.
std::vector<Option<EnergyOptions>>
energyOptionTable()
{
    const EnergyOptions d;
    const EnergyParameters& p = d.params;
    // clang-format off
    return {
        {"--source", "FILE", "Input",
         "the source shape M1, instead of the first positional argument",
         [](EnergyOptions& o, const std::string& v) { o.source = v; }},
        {"--target", "FILE", "Input",
         "the target shape M2, instead of the second positional argument",
         [](EnergyOptions& o, const std::string& v) { o.target = v; }},
        {"--grid", "NAME", "Input",
         "grid to read from both files (default: the only float grid of each file)",
         [](EnergyOptions& o, const std::string& v) { o.grid = v; }},
        {"--source-grid", "NAME", "Input", "grid to read from SOURCE (not with --grid)",
         [](EnergyOptions& o, const std::string& v) { o.sourceGrid = v; }},
        {"--target-grid", "NAME", "Input", "grid to read from TARGET (not with --grid)",
         [](EnergyOptions& o, const std::string& v) { o.targetGrid = v; }},
        {"--level", "L", "Domain and resolution",
         "lattice level: h = 2^-L in the unit box, 1..12 (default " +
             std::to_string(d.level) + ")",
         [](EnergyOptions& o, const std::string& v) { o.level = parseInt("--level", v); }},
        {"--margin", "X", "Domain and resolution",
         "space left on each side of the shapes' common bounding box in the unit box, "
         "[0, 0.5) (default " + formatNumber(d.margin) + ")",
         [](EnergyOptions& o, const std::string& v) { o.margin = parseDouble("--margin", v); }},
        {"--energy", "KIND", "Energy (paper tab:parameters)",
         "symmetric (eq:Esym) or directional (eq:Ecomparison) (default " +
             toString(d.kind) + ")",
         [](EnergyOptions& o, const std::string& v) {
             if (v != "symmetric" && v != "directional") {
                 throw UsageError("--energy expects 'symmetric' or 'directional', got '" + v +
                                  "'");
             }
             o.kind = parseEnergyKind(v);
         }},
        {"--c-match", "X", "Energy (paper tab:parameters)",
         "weight of the matching term (default " + formatNumber(p.cMatch) + ")",
         [](EnergyOptions& o, const std::string& v) {
             o.params.cMatch = parseDouble("--c-match", v);
         }},
        {"--c-mem", "X", "Energy (paper tab:parameters)",
         "weight of the membrane term (default " + formatNumber(p.cMem) + ")",
         [](EnergyOptions& o, const std::string& v) { o.params.cMem = parseDouble("--c-mem", v); }},
        {"--c-bend", "X", "Energy (paper tab:parameters)",
         "weight of the bending term (default " + formatNumber(p.cBend) + ")",
         [](EnergyOptions& o, const std::string& v) {
             o.params.cBend = parseDouble("--c-bend", v);
         }},
        {"--c-vol", "X", "Energy (paper tab:parameters)",
         "weight of the volume term (default " + formatNumber(p.cVol) + ")",
         [](EnergyOptions& o, const std::string& v) { o.params.cVol = parseDouble("--c-vol", v); }},
        {"--q", "X", "Energy (paper tab:parameters)",
         "matching exponent, weight sigma^-q (default " + formatNumber(p.q) + ")",
         [](EnergyOptions& o, const std::string& v) { o.params.q = parseDouble("--q", v); }},
        {"--theta", "X", "Energy (paper tab:parameters)",
         "volume exponent, weight sigma^theta (default " + formatNumber(p.theta) + ")",
         [](EnergyOptions& o, const std::string& v) { o.params.theta = parseDouble("--theta", v); }},
        {"--tau", "X", "Energy (paper tab:parameters)",
         "eigenvalue floor of the regularized shape operator, 1/unit-box length, > 0 (default " +
             formatNumber(p.tau) + ")",
         [](EnergyOptions& o, const std::string& v) { o.params.tau = parseDouble("--tau", v); }},
        {"--hessian-smoothing", "N", "Energy (paper tab:parameters)",
         "[1,2,1]/4 smoothing passes of the distance Hessian, >= 0 (default " +
             std::to_string(d.hessianSmoothing) + ")",
         [](EnergyOptions& o, const std::string& v) {
             o.hessianSmoothing = parseInt("--hessian-smoothing", v);
         }},
        {"--json", nullptr, "Output", "print the results as one JSON object",
         [](EnergyOptions& o, const std::string&) { o.json = true; }},
        {"--quiet", nullptr, "Output", "no progress messages on stderr (errors are still printed)",
         [](EnergyOptions& o, const std::string&) { o.quiet = true; }},
        {"--threads", "N", "Execution", "number of threads, 0 = all cores (default 0)",
         [](EnergyOptions& o, const std::string& v) { o.threads = parseThreads(v); }},
    };
    // clang-format on
}

////////////////////////////////////////////////////////////////////////////////
// The energy command

struct InputInfo
{
    std::string path, grid;
    double worldVoxelSize = 0;
    size_t activeVoxels = 0;
};

struct Timings
{
    double read = 0, place = 0, resample = 0, fields = 0, lattice = 0, energy = 0, total = 0;
};

void
printHuman(std::ostream& out, const EnergyOptions& o, const InputInfo (&in)[2],
           const UnitBoxPlacement& placement, double h, double sigma, size_t simplices,
           const EnergyTerms& t, double total, const Timings& time)
{
    out << "vdb_match energy: " << toString(o.kind) << " energy of phi = Id, level " << o.level
        << "\n";
    const char* roles[2] = {"source", "target"};
    for (int i = 0; i < 2; ++i) {
        out << "  " << roles[i] << ":  " << in[i].path << ", grid '" << in[i].grid
            << "', world voxel " << in[i].worldVoxelSize << ", resampled to " << in[i].activeVoxels
            << " voxels\n";
    }
    out << "  placement: unit = " << placement.scale << " * (world - " << placement.worldOrigin
        << "), margin " << placement.margin << "\n";
    out << "  h = " << h << ", sigma = " << sigma << ", simplices " << simplices
        << ", band simplices " << t.bandSimplices << ", inverted " << t.invertedSimplices << "\n";
    out << "  term         direct          inverse         sum\n";
    const char* names[4] = {"match", "mem", "bend", "vol"};
    const Real* halves[4] = {t.match, t.mem, t.bend, t.vol};
    for (int k = 0; k < 4; ++k) {
        out << "  " << names[k] << std::string(7 - std::string(names[k]).size(), ' ')
            << fixed("%15.8e", halves[k][0]) << " " << fixed("%15.8e", halves[k][1]) << " "
            << fixed("%15.8e", halves[k][0] + halves[k][1]) << "\n";
    }
    out << "  total  " << fixed("%15.8e", total) << "\n";
    out << "  time [s]: read " << fixed("%.3f", time.read) << ", place "
        << fixed("%.3f", time.place) << ", resample " << fixed("%.3f", time.resample) << ", fields "
        << fixed("%.3f", time.fields) << ", lattice " << fixed("%.3f", time.lattice) << ", energy "
        << fixed("%.3f", time.energy) << ", total " << fixed("%.3f", time.total) << "\n";
}

void
printJson(std::ostream& out, const EnergyOptions& o, const InputInfo (&in)[2],
          const UnitBoxPlacement& placement, double h, double sigma, size_t simplices,
          const EnergyTerms& t, double total, const Timings& time)
{
    const EnergyParameters& p = o.params;
    auto input = [](const InputInfo& i) {
        return Json{{"path", i.path},
                    {"grid", i.grid},
                    {"worldVoxelSize", i.worldVoxelSize},
                    {"activeVoxels", i.activeVoxels}};
    };
    auto pair = [](const Real* v) { return Json::array({v[0], v[1]}); };
    Json j;
    j["command"] = "energy";
    j["version"] = VDBMATCH_VERSION;
    j["energy"] = toString(o.kind);
    j["source"] = input(in[0]);
    j["target"] = input(in[1]);
    j["placement"] = Json{{"worldOrigin", jsonVec(placement.worldOrigin)},
                          {"scale", placement.scale},
                          {"margin", placement.margin}};
    j["parameters"] = energyParametersJson(p);
    j["parameters"]["hessianSmoothing"] = o.hessianSmoothing;
    j["level"] = o.level;
    j["h"] = h;
    j["sigma"] = sigma;
    j["simplices"] = simplices;
    j["bandSimplices"] = t.bandSimplices;
    j["invertedSimplices"] = t.invertedSimplices;
    j["terms"] = Json{{"match", pair(t.match)},
                      {"mem", pair(t.mem)},
                      {"bend", pair(t.bend)},
                      {"vol", pair(t.vol)}};
    j["total"] = total;
    j["timings"] =
        Json{{"read", time.read},     {"place", time.place},     {"resample", time.resample},
             {"fields", time.fields}, {"lattice", time.lattice}, {"energy", time.energy},
             {"total", time.total}};
    out << dumpJson(j);
}

int
runEnergy(const EnergyOptions& o, std::ostream& out, std::ostream& err)
{
    const Clock::time_point start = Clock::now();
    Timings time;
    auto progress = [&](const std::string& message) {
        if (!o.quiet) err << PROGRAM << ": " << message << std::endl;
    };
    if (o.threads < 0) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--threads must be >= 0, got " + std::to_string(o.threads));
    }
    if (o.level < 1 || o.level > MAX_ENERGY_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError,
                      "--level must be in [1, " + std::to_string(MAX_ENERGY_LEVEL) +
                          "] (energy evaluates a dense lattice of 6 * 8^level simplices), got " +
                          std::to_string(o.level));
    }
    if (o.hessianSmoothing < 0) {
        OPENVDB_THROW(openvdb::ValueError, "--hessian-smoothing must be >= 0, got " +
                                               std::to_string(o.hessianSmoothing));
    }
    o.params.validate();
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    SignalInterrupter interrupter;

    // 1. Read.
    InputInfo in[2];
    in[0].path = o.source;
    in[1].path = o.target;
    const std::string names[2] = {o.grid.empty() ? o.sourceGrid : o.grid,
                                  o.grid.empty() ? o.targetGrid : o.grid};
    openvdb::FloatGrid::Ptr inputs[2];
    Clock::time_point t0 = Clock::now();
    for (int i = 0; i < 2; ++i) {
        progress("reading " + in[i].path);
        inputs[i] = readLevelSet(in[i].path, names[i]);
        in[i].grid = inputs[i]->getName();
        in[i].worldVoxelSize = inputs[i]->voxelSize()[0];
        checkInterrupted();
    }
    time.read = secondsSince(t0);

    // 2. Place both shapes in the unit box and resample them at the level.
    t0 = Clock::now();
    const UnitBoxPlacement placement = placeInUnitBox(*inputs[0], *inputs[1], o.margin);
    time.place = secondsSince(t0);
    t0 = Clock::now();
    openvdb::FloatGrid::ConstPtr sdf[2];
    for (int i = 0; i < 2; ++i) {
        progress("resampling " + in[i].path + " at level " + std::to_string(o.level));
        openvdb::FloatGrid::Ptr g = resampleToUnitBox(*inputs[i], placement, o.level,
                                                      MIN_RESAMPLE_BAND_VOXELS, &interrupter);
        checkInterrupted();
        if (!g) throw Interrupted{}; // resampleToUnitBox returns null only when interrupted
        in[i].activeVoxels = g->activeVoxelCount();
        sdf[i] = g;
        inputs[i].reset();
    }
    time.resample = secondsSince(t0);

    // 3. Shape fields.
    t0 = Clock::now();
    progress("computing shape fields");
    ShapeFieldOptions fieldOptions;
    fieldOptions.tau = o.params.tau;
    fieldOptions.hessianSmoothing = o.hessianSmoothing;
    const FieldSampler<3>::Ptr shape1 = FieldSampler<3>::build({sdf[0]}, fieldOptions);
    checkInterrupted();
    const FieldSampler<3>::Ptr shape2 = FieldSampler<3>::build({sdf[1]}, fieldOptions);
    checkInterrupted();
    time.fields = secondsSince(t0);

    // 4. Lattice and energy of phi = Id.
    t0 = Clock::now();
    const SimplexLattice<3> lattice = SimplexLattice<3>::dense(o.level);
    time.lattice = secondsSince(t0);
    checkInterrupted();
    t0 = Clock::now();
    progress("evaluating the energy");
    const Energy<3> energy(lattice, *shape1, *shape2, o.params, o.kind);
    const NodeVectors<3> u = NodeVectors<3>::Zero(3, Eigen::Index(lattice.nodeCount()));
    EnergyTerms terms;
    const Real total = energy.value(u, &terms, /*threaded=*/true, &interrupter);
    checkInterrupted();
    time.energy = secondsSince(t0);
    time.total = secondsSince(start);

    if (o.json) {
        printJson(out, o, in, placement, lattice.h(), energy.sigma(), lattice.simplexCount(), terms,
                  total, time);
    } else {
        printHuman(out, o, in, placement, lattice.h(), energy.sigma(), lattice.simplexCount(),
                   terms, total, time);
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

EnergyOptions
parseEnergyOptions(int argc, const char* const* argv, int first)
{
    const std::vector<Option<EnergyOptions>> table = energyOptionTable();
    EnergyOptions o;
    const std::vector<std::string> positional = parseOptions(table, argc, argv, first, o);
    assignInputs(positional, o.source, o.target, "energy expects SOURCE.vdb TARGET.vdb");
    if (!o.grid.empty() && (!o.sourceGrid.empty() || !o.targetGrid.empty())) {
        throw UsageError("--grid cannot be combined with --source-grid or --target-grid");
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
