/// @file CliSupport.h
/// @brief What the vdb_match commands share: the option table and its CLI11 parser, number parsing,
///        help layout, SIGINT/SIGTERM handling, JSON and text formatting.
#pragma once

#include "Cli.h"

#include <vdbmatch/io/ShapeIO.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

extern const char* const PROGRAM;

////////////////////////////////////////////////////////////////////////////////
// Options

/// One option of a command: `--name VALUE` (or `--name=VALUE`), or a flag when metavar is null.
/// @a name is the option's spelling, or several separated by commas, the first the canonical one
/// and the others aliases ("--output,-o"). @a apply stores the value into the command's options
/// (Signature: void(T&, const string&)); it is called once per occurrence, in command-line order.
template <typename T> struct Option
{
    const char* name;
    const char* metavar; ///< nullptr for flags
    const char* group;
    std::string help; ///< with the default value
    std::function<void(T&, const std::string&)> apply;
};

/// The canonical spelling of an option: its name up to the first comma.
std::string canonicalName(const char* name);

/// An option of a table bound to one options object: what the CLI11 layer sees.
struct BoundOption
{
    std::string names; ///< "--output,-o": canonical first, then aliases
    const char* metavar;
    std::string group;
    std::string help;
    std::function<void(const std::string&)> apply;
};

/// Thrown by the parser on -h/--help (the caller prints the command's help page, exit 0).
struct HelpRequested
{
};
/// Thrown by the parser on --version (the caller prints the version, exit 0).
struct VersionRequested
{
};

/// Parses argv[first..argc) with CLI11 against @a options and returns the positional arguments.
/// Options apply in command-line order; a repeated option applies each time (the last wins);
/// `--` ends the options; -h/--help and --version throw HelpRequested / VersionRequested.
/// @throw UsageError on an unknown option (with the closest valid spelling), a missing value or
///        a value given to a flag
std::vector<std::string> parseCommandLine(const std::vector<BoundOption>& options, int argc,
                                          const char* const* argv, int first);

/// The grouped option lines of @a options, rendered by CLI11's help formatter (our layout: names
/// and metavar, then the help text wrapped at 100 columns), then -h/--help and --version.
std::string renderOptionHelp(const std::vector<BoundOption>& options);

/// The valid spelling in @a candidates closest to @a word (edit distance), or "" if none is
/// close enough to be a likely typo.
std::string closestSpelling(const std::string& word, const std::vector<std::string>& candidates);

/// The table bound to @a o.
template <typename T>
std::vector<BoundOption>
bindOptions(const std::vector<Option<T>>& table, T& o)
{
    std::vector<BoundOption> bound;
    bound.reserve(table.size());
    for (const Option<T>& opt : table) {
        auto apply = opt.apply;
        bound.push_back({opt.name, opt.metavar, opt.group, opt.help,
                         [apply, &o](const std::string& v) { apply(o, v); }});
    }
    return bound;
}

/// Applies the options of argv[first..argc) to @a o and returns the positional arguments
/// (see parseCommandLine).
template <typename T>
std::vector<std::string>
parseOptions(const std::vector<Option<T>>& table, int argc, const char* const* argv, int first,
             T& o)
{
    return parseCommandLine(bindOptions(table, o), argc, argv, first);
}

/// The help lines of an option table, grouped (see renderOptionHelp).
template <typename T>
std::string
optionHelp(const std::vector<Option<T>>& table)
{
    T unused;
    return renderOptionHelp(bindOptions(table, unused));
}

/// The options of a table as data (commandOptions).
template <typename T>
std::vector<OptionDescription>
describeOptions(const std::vector<Option<T>>& table)
{
    std::vector<OptionDescription> out;
    for (const Option<T>& opt : table) {
        OptionDescription d;
        d.name = canonicalName(opt.name);
        d.metavar = opt.metavar ? opt.metavar : "";
        d.values = opt.metavar ? 1 + int(std::count(d.metavar.begin(), d.metavar.end(), ' ')) : 0;
        d.group = opt.group;
        d.help = opt.help;
        out.push_back(std::move(d));
    }
    return out;
}

/// Fills @a source and @a target, those not given as --source/--target, from @a positional in
/// order. @throw UsageError "WHAT, got N file argument(s)" unless the counts agree
void assignInputs(const std::vector<std::string>& positional, std::string& source,
                  std::string& target, const std::string& what);

/// Reads one input shape exactly as `match` does (readShape: .vdb level sets and one-layer 2D
/// slices, .obj/.ply/.stl meshes, .polyline/.txt curves); used by `match` and `energy`.
/// @throw UsageError if @a gridName is given for a file that is not a .vdb
/// @throw as readShape
/// @a isoValue (--iso-value) converts a .vdb density to the level set of that iso-surface.
Shape readInputShape(const std::string& path, const std::string& gridName,
                     std::optional<double> isoValue = std::nullopt);

/// Checks --iso-value against the inputs: it needs a .vdb among them.
/// @throw UsageError otherwise
void checkIsoValueInputs(const std::optional<double>& isoValue, const std::string& source,
                         const std::string& target);

/// The command line as typed: argv joined by spaces.
std::string commandLine(int argc, const char* const* argv);

/// Creates the output directory @a dir (and its parents) if it does not exist.
/// @throw openvdb::IoError "cannot create the output directory 'DIR': REASON" if it is not a
///        directory afterwards
void createOutputDirectory(const std::string& dir);

/// Parses a finite number / an integer for option @a option.
/// @throw UsageError if @a text is not one
double parseDouble(const std::string& option, const std::string& text);
int parseInt(const std::string& option, const std::string& text);
/// Parses an on|off switch for option @a option.
/// @throw UsageError if @a text is neither
bool parseOnOff(const std::string& option, const std::string& text);
/// Largest --threads accepted (0 = all cores); TBB allocates per requested thread.
constexpr int MAX_THREADS = 1024;
/// Parses --threads: an integer in [0, MAX_THREADS].
/// @throw UsageError otherwise
int parseThreads(const std::string& text);
/// Shortest decimal form of x ("4.096").
std::string formatNumber(double x);
/// One help entry: the left column, then @a text wrapped at 100 columns.
std::string wrapHelp(const std::string& left, const std::string& text);

////////////////////////////////////////////////////////////////////////////////
// Interruption

/// Installs SIGINT/SIGTERM handlers that raise the interruption flag, while alive; a second
/// signal terminates at once. Under an embedding's hooks (HooksScope) only if they ask for
/// signal handling, and a second signal only raises the flag again.
class SignalScope
{
public:
    SignalScope();
    ~SignalScope();
    SignalScope(const SignalScope&) = delete;
    SignalScope& operator=(const SignalScope&) = delete;

private:
    bool mInstalled;
    void (*mInt)(int) = nullptr;
    void (*mTerm)(int) = nullptr;
};

/// Makes @a hooks those of the commands run while alive (run() with RunHooks).
class HooksScope
{
public:
    explicit HooksScope(const RunHooks* hooks);
    ~HooksScope();
    HooksScope(const HooksScope&) = delete;
    HooksScope& operator=(const HooksScope&) = delete;

private:
    const RunHooks* mPrevious;
};

/// The hooks of the running command, or nullptr (the CLI).
const RunHooks* currentHooks();

/// True once a signal arrived in the current SignalScope, or the embedding's cancel flag is set.
bool wasSignalled();

/// An interrupter that fires once a signal arrived.
class SignalInterrupter final : public openvdb::util::NullInterrupter
{
public:
    bool wasInterrupted(int = -1) override { return wasSignalled(); }
};

/// Thrown between stages when a signal arrived (exit code EXIT_INTERRUPTED).
struct Interrupted
{
};

/// Throws Interrupted if a signal arrived (or the embedding's cancel flag is set).
void checkInterrupted();

////////////////////////////////////////////////////////////////////////////////
// Formatting

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0);
/// A duration as "12.3s", "4m05s" or "1h02m" ("?" if not finite).
std::string duration(double seconds);

/// An exclusive advisory lock (flock) on OUTDIR/.vdb_match.lock while a command writes there;
/// the kernel releases it when the process ends, however it ends. Not inherited by children.
class OutputLock
{
public:
    /// @throw openvdb::IoError if the lock file cannot be created or another process holds it
    explicit OutputLock(const std::string& dir);
    ~OutputLock();
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

private:
    int mFd = -1;
};

/// JSON documents of the commands: nlohmann's ordered JSON keeps keys in insertion order; numbers
/// are written in their shortest round-trip form, NaN and infinities as null.
using Json = nlohmann::ordered_json;
/// [x, y, z].
Json jsonVec(const openvdb::Vec3d& v);
/// The energy coefficients of tab:parameters: cMatch, cMem, cBend, cVol, q, theta, tau,
/// sigmaFactor, and membraneSaturation, an addition (the "parameters" of report.json and of
/// `energy --json`).
Json energyParametersJson(const EnergyParameters& p);
/// The document indented by 2, with a final newline; invalid UTF-8 in strings is replaced.
std::string dumpJson(const Json& j);
/// printf-style formatting of one number.
std::string fixed(const char* format, double x);
/// One line: the exception message without OpenVDB's "XxxError: " prefix and newlines.
std::string oneLine(const std::string& what);
/// An input shape in report.json and `energy --json`: path, format, grid, vertices, elements,
/// isoValue (a density read at an iso-value), pieces and smallPieces (geometry/SurfacePieces.h).
Json shapeJson(const Shape& in);
/// The warning, without "vdb_match: warning: ", for a shape with a piece below
/// SMALL_PIECE_SHARE of its area or length (geometry/SurfacePieces.h); "" if it has none.
/// @param role  "source" or "target"
std::string smallPiecesWarning(const Shape& in, const char* role);

} // namespace cli
} // namespace vdbmatch
