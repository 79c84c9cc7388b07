/// @file Cli.h
/// @brief The vdb_match command line: one option table per command (parsed with CLI11, which also
///        renders its help page), dispatch, and the subcommands.
///
/// Usage: `vdb_match [match] SOURCE TARGET -o OUTDIR [options]`,
/// `vdb_match energy SOURCE TARGET [options]`,
/// `vdb_match consistency PHI.vdb PSI.vdb --source M1 --target M2 [options]`,
/// `vdb_match slice PHI.vdb --source M1 --target M2 -o OUT.exr [options]`,
/// `vdb_match apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse] [options]`,
/// `vdb_match --help`, `--version`.
/// Results go to the output stream, progress and errors to the error stream (errors as one line
/// `vdb_match: error: ...`). See docs/cli.md.
#pragma once

#include <vdbmatch/Parameters.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>

namespace vdbmatch {
namespace cli {

/// Process exit codes, documented in --help and docs/cli.md.
enum ExitCode : int {
    EXIT_OK = 0,
    EXIT_USAGE = 1,         ///< unknown option, missing argument, bad number, contradiction
    EXIT_IO = 2,            ///< missing or unreadable file
    EXIT_INVALID_INPUT = 3, ///< not a level set, ambiguous grid, NaN, empty, out-of-range values
    EXIT_NOT_CONVERGED = 4, ///< reserved for `match --strict`
    EXIT_INTERRUPTED = 5    ///< SIGINT or SIGTERM
};

/// A command-line error (exit code EXIT_USAGE).
class UsageError : public std::runtime_error
{
public:
    using std::runtime_error::runtime_error;
};

/// Options of the `energy` command, with their defaults. Energy coefficients left unset take
/// the defaults of the inputs' dimension (tab:parameters), as in `match`.
struct EnergyOptions
{
    std::string source, target; ///< input files (any shape `match` reads)
    std::string grid;           ///< --grid: grid name in both files
    std::string sourceGrid;     ///< --source-grid
    std::string targetGrid;     ///< --target-grid
    int level = 6;              ///< lattice level, h = 2^-level
    double margin = DEFAULT_UNIT_BOX_MARGIN;
    std::optional<double> isoValue; ///< --iso-value: densities converted at this value
    EnergyKind kind = EnergyKind::Symmetric;
    std::optional<double> cMatch, cMem, cBend, cVol, q, theta;
    double tau = EnergyParameters().tau;
    int hessianSmoothing = 0; ///< ShapeFieldOptions::hessianSmoothing
    int threads = 0;          ///< 0: all cores
    bool json = false;
    bool quiet = false;

    /// The energy parameters for inputs of dimension @a dim: the options given over
    /// EnergyParameters::defaults(dim).
    EnergyParameters parameters(int dim) const;
};

/// Parses the arguments that follow `energy` (argv[first..argc)).
/// @throw UsageError on an unknown option, a missing value or argument, a malformed number, or
/// contradictory options. Range checks are left to the library (exit code EXIT_INVALID_INPUT).
EnergyOptions parseEnergyOptions(int argc, const char* const* argv, int first);

/// The overview: usage lines, what each command does, exit codes.
std::string helpText();
/// The help page of one command (`vdb_match COMMAND --help`): usage, description, its options
/// grouped with their defaults, exit codes. The overview for an unknown name.
std::string commandHelpText(const std::string& command);
/// The grouped option lines of `energy` and of `match`, with their defaults.
std::string energyOptionHelp();
std::string matchOptionHelp();
/// The grouped option lines of `consistency` and of `slice`, with their defaults.
std::string consistencyOptionHelp();
std::string sliceOptionHelp();
/// The option lines of `texture`, with their defaults.
std::string textureOptionHelp();
/// The option lines of `apply`, with their defaults.
std::string applyOptionHelp();
/// The help page of `apply` (usage, directions, options).
std::string applyHelpText();

/// The preview path of a slice channel: OUT.exr -> OUT.<channel>.png.
std::string slicePreviewPath(const std::string& exrPath, const std::string& channel);

/// The commands, on argv[first..argc): return the exit code; results to @a out, progress to
/// @a err. They throw UsageError, Interrupted and library exceptions, mapped to exit codes by
/// run().
int runEnergyCommand(int argc, const char* const* argv, int first, std::ostream& out,
                     std::ostream& err);
int runMatchCommand(int argc, const char* const* argv, int first, std::ostream& out,
                    std::ostream& err);
int runConsistencyCommand(int argc, const char* const* argv, int first, std::ostream& out,
                          std::ostream& err);
int runSliceCommand(int argc, const char* const* argv, int first, std::ostream& out,
                    std::ostream& err);
int runApplyCommand(int argc, const char* const* argv, int first, std::ostream& out,
                    std::ostream& err);
int runTextureCommand(int argc, const char* const* argv, int first, std::ostream& out,
                      std::ostream& err);

/// Runs the command line and returns the exit code. Writes results to @a out and progress and
/// errors to @a err. Installs SIGINT/SIGTERM handlers for the duration of a command.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

} // namespace cli
} // namespace vdbmatch
