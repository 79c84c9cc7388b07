/// @file Cli.cc
/// @brief Option table, parsing, help and the `energy` command of vdb_match.
#include "Cli.h"

#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>
#include <tbb/global_control.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

const char* const PROGRAM = "vdb_match";

////////////////////////////////////////////////////////////////////////////////
// Option table

/// One option of a command: `--name VALUE` (or `--name=VALUE`), or a flag when metavar is null.
struct Option
{
    const char* name;
    const char* metavar; ///< nullptr for flags
    const char* group;
    std::string help; ///< with the default value
    std::function<void(EnergyOptions&, const std::string&)> apply;
};

std::string
formatNumber(double x)
{
    std::ostringstream s;
    s << x;
    return s.str();
}

double
parseDouble(const std::string& option, const std::string& text)
{
    errno = 0;
    char* end = nullptr;
    const double x = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(x)) {
        throw UsageError(option + " expects a finite number, got '" + text + "'");
    }
    return x;
}

int
parseInt(const std::string& option, const std::string& text)
{
    errno = 0;
    char* end = nullptr;
    const long x = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE ||
        x < std::numeric_limits<int>::min() || x > std::numeric_limits<int>::max()) {
        throw UsageError(option + " expects an integer, got '" + text + "'");
    }
    return int(x);
}

/// The options of `energy`, in help order; help strings show the defaults of @a d.
std::vector<Option>
energyOptionTable()
{
    const EnergyOptions d;
    const EnergyParameters& p = d.params;
    // clang-format off
    return {
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
         [](EnergyOptions& o, const std::string& v) { o.threads = parseInt("--threads", v); }},
    };
    // clang-format on
}

////////////////////////////////////////////////////////////////////////////////
// Interruption

std::atomic<bool> sInterrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void
onSignal(int sig)
{
    sInterrupted.store(true);
    std::signal(sig, SIG_DFL); // a second signal terminates at once
}

/// Installs the SIGINT/SIGTERM handlers while alive.
class SignalScope
{
public:
    SignalScope()
    {
        sInterrupted.store(false);
        mInt = std::signal(SIGINT, onSignal);
        mTerm = std::signal(SIGTERM, onSignal);
    }
    ~SignalScope()
    {
        std::signal(SIGINT, mInt);
        std::signal(SIGTERM, mTerm);
    }
    SignalScope(const SignalScope&) = delete;
    SignalScope& operator=(const SignalScope&) = delete;

private:
    void (*mInt)(int);
    void (*mTerm)(int);
};

class SignalInterrupter final : public openvdb::util::NullInterrupter
{
public:
    bool wasInterrupted(int = -1) override { return sInterrupted.load(); }
};

/// Thrown between stages when a signal arrived (exit code EXIT_INTERRUPTED).
struct Interrupted
{
};

void
checkInterrupted()
{
    if (sInterrupted.load()) throw Interrupted{};
}

////////////////////////////////////////////////////////////////////////////////
// Output helpers

using Clock = std::chrono::steady_clock;

double
secondsSince(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string
jsonString(const std::string& s)
{
    std::string out = "\"";
    for (const char c : s) {
        switch (c) {
        case '"':
            out += "\\\"";
            break;
        case '\\':
            out += "\\\\";
            break;
        case '\n':
            out += "\\n";
            break;
        case '\t':
            out += "\\t";
            break;
        default:
            if (static_cast<unsigned char>(c) < 0x20) {
                char buf[8];
                std::snprintf(buf, sizeof(buf), "\\u%04x", c);
                out += buf;
            } else {
                out += c;
            }
        }
    }
    return out + "\"";
}

/// A JSON number with 17 significant digits; null if not finite.
std::string
jsonNumber(double x)
{
    if (!std::isfinite(x)) return "null";
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.17g", x);
    return buf;
}

std::string
jsonVec(const openvdb::Vec3d& v)
{
    return "[" + jsonNumber(v[0]) + ", " + jsonNumber(v[1]) + ", " + jsonNumber(v[2]) + "]";
}

std::string
fixed(const char* format, double x)
{
    char buf[64];
    std::snprintf(buf, sizeof(buf), format, x);
    return buf;
}

/// One line: the exception message without OpenVDB's "XxxError: " prefix and newlines.
std::string
oneLine(const std::string& what)
{
    std::string s = what;
    const size_t colon = s.find(": ");
    if (colon != std::string::npos && colon >= 5 && s.compare(colon - 5, 5, "Error") == 0 &&
        s.find(' ') > colon) {
        s = s.substr(colon + 2);
    }
    for (char& c : s) {
        if (c == '\n' || c == '\r') c = ' ';
    }
    return s;
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
        return "{\"path\": " + jsonString(i.path) + ", \"grid\": " + jsonString(i.grid) +
               ", \"worldVoxelSize\": " + jsonNumber(i.worldVoxelSize) +
               ", \"activeVoxels\": " + std::to_string(i.activeVoxels) + "}";
    };
    auto pair = [](const Real* v) {
        return "[" + jsonNumber(v[0]) + ", " + jsonNumber(v[1]) + "]";
    };
    out << "{\n"
        << "  \"command\": \"energy\",\n"
        << "  \"version\": " << jsonString(VDBMATCH_VERSION) << ",\n"
        << "  \"energy\": " << jsonString(toString(o.kind)) << ",\n"
        << "  \"source\": " << input(in[0]) << ",\n"
        << "  \"target\": " << input(in[1]) << ",\n"
        << "  \"placement\": {\"worldOrigin\": " << jsonVec(placement.worldOrigin)
        << ", \"scale\": " << jsonNumber(placement.scale)
        << ", \"margin\": " << jsonNumber(placement.margin) << "},\n"
        << "  \"parameters\": {\"cMatch\": " << jsonNumber(p.cMatch)
        << ", \"cMem\": " << jsonNumber(p.cMem) << ", \"cBend\": " << jsonNumber(p.cBend)
        << ", \"cVol\": " << jsonNumber(p.cVol) << ", \"q\": " << jsonNumber(p.q)
        << ", \"theta\": " << jsonNumber(p.theta) << ", \"tau\": " << jsonNumber(p.tau)
        << ", \"sigmaFactor\": " << jsonNumber(p.sigmaFactor)
        << ", \"hessianSmoothing\": " << o.hessianSmoothing << "},\n"
        << "  \"level\": " << o.level << ",\n"
        << "  \"h\": " << jsonNumber(h) << ",\n"
        << "  \"sigma\": " << jsonNumber(sigma) << ",\n"
        << "  \"simplices\": " << simplices << ",\n"
        << "  \"bandSimplices\": " << t.bandSimplices << ",\n"
        << "  \"invertedSimplices\": " << t.invertedSimplices << ",\n"
        << "  \"terms\": {\"match\": " << pair(t.match) << ", \"mem\": " << pair(t.mem)
        << ", \"bend\": " << pair(t.bend) << ", \"vol\": " << pair(t.vol) << "},\n"
        << "  \"total\": " << jsonNumber(total) << ",\n"
        << "  \"timings\": {\"read\": " << jsonNumber(time.read)
        << ", \"place\": " << jsonNumber(time.place)
        << ", \"resample\": " << jsonNumber(time.resample)
        << ", \"fields\": " << jsonNumber(time.fields)
        << ", \"lattice\": " << jsonNumber(time.lattice)
        << ", \"energy\": " << jsonNumber(time.energy) << ", \"total\": " << jsonNumber(time.total)
        << "}\n"
        << "}\n";
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

////////////////////////////////////////////////////////////////////////////////
// Help

std::string
wrapHelp(const std::string& left, const std::string& text)
{
    constexpr size_t HELP_COLUMN = 26;
    constexpr size_t LINE_WIDTH = 100;
    std::string out = "  " + left;
    if (out.size() + 1 > HELP_COLUMN) {
        out += "\n" + std::string(HELP_COLUMN, ' ');
    } else {
        out += std::string(HELP_COLUMN - out.size(), ' ');
    }
    size_t column = HELP_COLUMN;
    std::istringstream words(text);
    std::string word;
    bool firstWord = true;
    while (words >> word) {
        if (!firstWord && column + 1 + word.size() > LINE_WIDTH) {
            out += "\n" + std::string(HELP_COLUMN, ' ');
            column = HELP_COLUMN;
            firstWord = true;
        }
        if (!firstWord) {
            out += ' ';
            ++column;
        }
        out += word;
        column += word.size();
        firstWord = false;
    }
    return out + "\n";
}

} // namespace

std::string
helpText()
{
    std::string s;
    s += std::string(PROGRAM) + " " + VDBMATCH_VERSION +
         ": smooth invertible matching of closed surfaces given as OpenVDB level sets\n\n";
    s += "Usage:\n";
    s += "  vdb_match COMMAND [options] ARGS...\n";
    s += "  vdb_match --help | --version\n\n";
    s += "Commands:\n";
    s += wrapHelp("energy SOURCE.vdb TARGET.vdb",
                  "place both level sets in the unit box, resample them at --level and print "
                  "the terms of the matching energy of the identity deformation (phi = Id)");
    s += "\nOptions of energy, as --name VALUE or --name=VALUE.\n";
    const std::vector<Option> table = energyOptionTable();
    std::string group;
    for (const Option& opt : table) {
        if (group != opt.group) {
            group = opt.group;
            s += "\n" + group + ":\n";
        }
        s += wrapHelp(std::string(opt.name) + (opt.metavar ? " " + std::string(opt.metavar) : ""),
                      opt.help);
    }
    s += "\nOther:\n";
    s += wrapHelp("-h, --help", "print this help and exit");
    s += wrapHelp("--version", "print the version and exit");
    s += "\nExit codes:\n";
    s += wrapHelp("0", "success");
    s += wrapHelp("1", "usage error: unknown option, missing argument, malformed number, "
                       "contradictory options");
    s += wrapHelp("2", "I/O error: missing or unreadable file");
    s += wrapHelp("3", "invalid input: not a level set, several grids and no --grid, NaN or "
                       "inf, empty grid, non-uniform voxels, open surface, parameter out of "
                       "range");
    s += wrapHelp("5", "interrupted (SIGINT, SIGTERM)");
    s += "\nErrors are printed to stderr as one line 'vdb_match: error: ...'.\n";
    return s;
}

EnergyOptions
parseEnergyOptions(int argc, const char* const* argv, int first)
{
    const std::vector<Option> table = energyOptionTable();
    EnergyOptions o;
    std::vector<std::string> positional;
    bool optionsDone = false;
    for (int i = first; i < argc; ++i) {
        const std::string arg = argv[i];
        if (optionsDone || arg.size() < 2 || arg[0] != '-') {
            positional.push_back(arg);
            continue;
        }
        if (arg == "--") {
            optionsDone = true;
            continue;
        }
        const size_t eq = arg.find('=');
        const std::string name = arg.substr(0, eq);
        const Option* opt = nullptr;
        for (const Option& candidate : table) {
            if (name == candidate.name) opt = &candidate;
        }
        if (!opt) throw UsageError("unknown option '" + name + "' (see vdb_match --help)");
        std::string value;
        if (!opt->metavar) {
            if (eq != std::string::npos) throw UsageError(name + " takes no value");
        } else if (eq != std::string::npos) {
            value = arg.substr(eq + 1);
        } else if (i + 1 < argc) {
            value = argv[++i];
        } else {
            throw UsageError(name + " expects a value " + opt->metavar);
        }
        opt->apply(o, value);
    }
    if (positional.size() != 2) {
        throw UsageError("energy expects SOURCE.vdb TARGET.vdb, got " +
                         std::to_string(positional.size()) + " file argument(s)");
    }
    o.source = positional[0];
    o.target = positional[1];
    if (!o.grid.empty() && (!o.sourceGrid.empty() || !o.targetGrid.empty())) {
        throw UsageError("--grid cannot be combined with --source-grid or --target-grid");
    }
    return o;
}

int
run(int argc, const char* const* argv, std::ostream& out, std::ostream& err)
{
    auto fail = [&](int code, const std::string& message) {
        err << PROGRAM << ": error: " << oneLine(message) << std::endl;
        return code;
    };
    try {
        if (argc < 2) throw UsageError("missing command (see vdb_match --help)");
        const std::string command = argv[1];
        if (command == "-h" || command == "--help" || command == "help") {
            out << helpText();
            return EXIT_OK;
        }
        if (command == "--version") {
            out << PROGRAM << " " << VDBMATCH_VERSION << " (OpenVDB "
                << openvdb::getLibraryVersionString() << ")\n";
            return EXIT_OK;
        }
        if (command == "energy") {
            for (int i = 2; i < argc; ++i) {
                const std::string arg = argv[i];
                if (arg == "--") break;
                if (arg == "-h" || arg == "--help") {
                    out << helpText();
                    return EXIT_OK;
                }
            }
            const EnergyOptions options = parseEnergyOptions(argc, argv, 2);
            openvdb::initialize();
            SignalScope signals;
            return runEnergy(options, out, err);
        }
        if (!command.empty() && command[0] == '-') {
            throw UsageError("unknown option '" + command +
                             "' before the command (see vdb_match "
                             "--help)");
        }
        throw UsageError("unknown command '" + command + "' (see vdb_match --help)");
    } catch (const UsageError& e) {
        return fail(EXIT_USAGE, e.what());
    } catch (const Interrupted&) {
        return fail(EXIT_INTERRUPTED, "interrupted");
    } catch (const openvdb::IoError& e) {
        return fail(EXIT_IO, e.what());
    } catch (const openvdb::Exception& e) {
        return fail(EXIT_INVALID_INPUT, e.what());
    } catch (const std::bad_alloc&) {
        return fail(EXIT_INVALID_INPUT, "out of memory (try a lower --level)");
    } catch (const std::exception& e) {
        return fail(EXIT_INVALID_INPUT, e.what());
    }
}

} // namespace cli
} // namespace vdbmatch
