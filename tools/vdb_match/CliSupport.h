/// @file CliSupport.h
/// @brief What the vdb_match commands share: the option table and its parser, number parsing,
///        help layout, SIGINT/SIGTERM handling, JSON and text formatting.
#pragma once

#include "Cli.h"

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

extern const char* const PROGRAM;

////////////////////////////////////////////////////////////////////////////////
// Options

/// One option of a command: `--name VALUE` (or `--name=VALUE`), or a flag when metavar is null.
/// @a apply stores the value into the command's options (Signature: void(T&, const string&)).
template <typename T> struct Option
{
    const char* name;
    const char* metavar; ///< nullptr for flags
    const char* group;
    std::string help; ///< with the default value
    std::function<void(T&, const std::string&)> apply;
};

/// Applies the options of argv[first..argc) to @a o and returns the positional arguments.
/// `--` ends the options; `-o` is short for `--output` (in tables that have it).
/// @throw UsageError on an unknown option or a missing or unexpected value
template <typename T>
std::vector<std::string>
parseOptions(const std::vector<Option<T>>& table, int argc, const char* const* argv, int first,
             T& o)
{
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
        const std::string name = arg == "-o" ? std::string("--output") : arg.substr(0, eq);
        const Option<T>* opt = nullptr;
        for (const Option<T>& candidate : table) {
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
    return positional;
}

/// The help lines of an option table, grouped.
template <typename T> std::string optionHelp(const std::vector<Option<T>>& table);

/// The command line as typed: argv joined by spaces.
std::string commandLine(int argc, const char* const* argv);

/// Parses a finite number / an integer for option @a option.
/// @throw UsageError if @a text is not one
double parseDouble(const std::string& option, const std::string& text);
int parseInt(const std::string& option, const std::string& text);
/// Largest --threads accepted (0 = all cores); TBB allocates per requested thread.
constexpr int MAX_THREADS = 1024;
/// Parses --threads: an integer in [0, MAX_THREADS].
/// @throw UsageError otherwise
int parseThreads(const std::string& text);
/// Shortest decimal form of x ("4.096").
std::string formatNumber(double x);
/// One help entry: the left column, then @a text wrapped at 100 columns.
std::string wrapHelp(const std::string& left, const std::string& text);

template <typename T>
std::string
optionHelp(const std::vector<Option<T>>& table)
{
    std::string s, group;
    for (const Option<T>& opt : table) {
        if (group != opt.group) {
            group = opt.group;
            s += "\n" + group + ":\n";
        }
        s += wrapHelp(std::string(opt.name) + (opt.metavar ? " " + std::string(opt.metavar) : ""),
                      opt.help);
    }
    return s;
}

////////////////////////////////////////////////////////////////////////////////
// Interruption

/// Installs SIGINT/SIGTERM handlers that raise the interruption flag, while alive; a second
/// signal terminates at once.
class SignalScope
{
public:
    SignalScope();
    ~SignalScope();
    SignalScope(const SignalScope&) = delete;
    SignalScope& operator=(const SignalScope&) = delete;

private:
    void (*mInt)(int);
    void (*mTerm)(int);
};

/// True once a signal arrived in the current SignalScope.
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

/// Throws Interrupted if a signal arrived.
void checkInterrupted();

////////////////////////////////////////////////////////////////////////////////
// Formatting

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0);

/// JSON documents of the commands: nlohmann's ordered JSON keeps keys in insertion order; numbers
/// are written in their shortest round-trip form, NaN and infinities as null.
using Json = nlohmann::ordered_json;
/// [x, y, z].
Json jsonVec(const openvdb::Vec3d& v);
/// The energy coefficients of tab:parameters: cMatch, cMem, cBend, cVol, q, theta, tau,
/// sigmaFactor (the "parameters" of report.json and of `energy --json`).
Json energyParametersJson(const EnergyParameters& p);
/// The document indented by 2, with a final newline; invalid UTF-8 in strings is replaced.
std::string dumpJson(const Json& j);
/// printf-style formatting of one number.
std::string fixed(const char* format, double x);
/// One line: the exception message without OpenVDB's "XxxError: " prefix and newlines.
std::string oneLine(const std::string& what);

} // namespace cli
} // namespace vdbmatch
