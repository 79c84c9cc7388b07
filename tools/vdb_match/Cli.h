/// @file Cli.h
/// @brief The vdb_match command line: one option table per command (parsed with CLI11, which also
///        renders its help page), dispatch, and the subcommands.
///
/// Usage: `vdb_match [match] SOURCE TARGET -o OUTDIR [options]`,
/// `vdb_match energy SOURCE TARGET [options]`,
/// `vdb_match consistency PHI.vdb PSI.vdb --source M1 --target M2 [options]`,
/// `vdb_match slice PHI.vdb --source M1 --target M2 -o OUT.exr [options]`,
/// `vdb_match apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse] [options]`,
/// `vdb_match batch (--all-pairs FILES... | --template T FILES... | --sequence P --frames A-B)
///  -o OUTDIR [options] [-- MATCH OPTIONS]`, `vdb_match batch status|collect OUTDIR`,
/// `vdb_match --help`, `--version`.
/// Results go to the output stream, progress and errors to the error stream (errors as one line
/// `vdb_match: error: ...`). See docs/cli.md.
#pragma once

#include <vdbmatch/Parameters.h>
#include <vdbmatch/geometry/SurfaceNoise.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <atomic>
#include <functional>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

/// Process exit codes, documented in --help and docs/cli.md.
enum ExitCode : int {
    EXIT_OK = 0,
    EXIT_USAGE = 1,         ///< unknown option, missing argument, bad number, contradiction
    EXIT_IO = 2,            ///< missing or unreadable file
    EXIT_INVALID_INPUT = 3, ///< not a level set, ambiguous grid, NaN, empty, out-of-range values
    EXIT_NOT_CONVERGED = 4, ///< reserved for `match --strict`
    EXIT_INTERRUPTED = 5,   ///< SIGINT or SIGTERM
    EXIT_JOBS_FAILED = 6    ///< batch: every job ran, some failed (listed in the summary)
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
    double membraneSaturation = 0; ///< --membrane-saturation (0: the paper's membrane)
    int hessianSmoothing = 0;      ///< ShapeFieldOptions::hessianSmoothing
    double noiseSmoothing = 0;     ///< --noise-smoothing (MatchOptions::hessianNoiseFactor)
    std::optional<double> latticeNoiseSmoothing;        ///< --lattice-noise-smoothing (as match's)
    double noiseBending = DEFAULT_NOISE_BENDING_PASSES; ///< --noise-bending (as match's)
    int threads = 0;                                    ///< 0: all cores
    bool json = false;
    bool quiet = false;

    /// The energy parameters for inputs of dimension @a dim: the options given over
    /// EnergyParameters::defaults(dim).
    EnergyParameters parameters(int dim) const;
    /// --lattice-noise-smoothing, or match's default for @a dim.
    double latticeNoiseFactor(int dim) const;
};

/// Parses the arguments that follow `energy` (argv[first..argc)).
/// @throw UsageError on an unknown option, a missing value or argument, a malformed number, or
/// contradictory options. Range checks are left to the library (exit code EXIT_INVALID_INPUT).
EnergyOptions parseEnergyOptions(int argc, const char* const* argv, int first);

/// One option of a command, as data: for programs that build command lines (the Python
/// module's keywords) and for documentation.
struct OptionDescription
{
    std::string name;    ///< canonical spelling, "--energy-tolerance"
    std::string metavar; ///< "X", "A.csv B.csv"; empty for a flag
    int values = 0;      ///< number of values it takes (0 for a flag)
    std::string group;   ///< help group
    std::string help;    ///< help text, with the default
};

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
/// The option tables as data (commandOptions).
std::vector<OptionDescription> matchOptionDescriptions();
std::vector<OptionDescription> energyOptionDescriptions();
std::vector<OptionDescription> consistencyOptionDescriptions();
std::vector<OptionDescription> sliceOptionDescriptions();
std::vector<OptionDescription> textureOptionDescriptions();
std::vector<OptionDescription> applyOptionDescriptions();
std::vector<OptionDescription> batchOptionDescriptions();
/// The option lines of `batch`, with their defaults.
std::string batchOptionHelp();
/// The help page of `apply` (usage, directions, options).
std::string applyHelpText();

/// The options of @a command ("match", "energy", "consistency", "slice", "texture", "apply"),
/// in the order of its help page; empty for an unknown command.
std::vector<OptionDescription> commandOptions(const std::string& command);

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
int runBatchCommand(int argc, const char* const* argv, int first, std::ostream& out,
                    std::ostream& err);

/// Runs the command line and returns the exit code. Writes results to @a out and progress and
/// errors to @a err. Installs SIGINT/SIGTERM handlers for the duration of a command.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err);

/// A progress event of `match`, for a program that embeds the command line (RunHooks).
struct ProgressEvent
{
    enum class Kind {
        Message,    ///< a stage: reading, writing, ...
        LevelStart, ///< a level's lattice is built
        Iteration,  ///< one descent iteration done (every iteration, whatever --progress-every)
        LevelEnd    ///< a level's descent ended
    };
    Kind kind = Kind::Message;
    int level = 0;             ///< the level (LevelStart, Iteration, LevelEnd)
    int firstLevel = 0;        ///< the run's first level
    int lastLevel = 0;         ///< the run's last level
    int iteration = 0;         ///< Iteration, LevelEnd: the level's iteration count
    double energy = 0;         ///< Iteration, LevelEnd: E at that iteration
    double elapsedSeconds = 0; ///< since the match started
    double secondsLeft = -1;   ///< estimate of the time left (-1: none yet)
    std::string text;          ///< what the command prints for it, without "vdb_match: "
};

/// What a program that embeds the command line (the Python module) hands to run().
struct RunHooks
{
    /// Called on the thread that called run(), for every ProgressEvent of `match`.
    std::function<void(const ProgressEvent&)> progress;
    /// When set (from any thread), the command stops as on SIGINT (exit code EXIT_INTERRUPTED).
    const std::atomic<bool>* cancel = nullptr;
    /// Install SIGINT/SIGTERM handlers for the command, as the CLI does; unlike the CLI's, a
    /// second signal does not terminate the process. False leaves the caller's handlers alone.
    bool handleSignals = true;
};

/// run() for an embedding: the same commands, exit codes and outputs, with @a hooks.
int run(int argc, const char* const* argv, std::ostream& out, std::ostream& err,
        const RunHooks& hooks);

} // namespace cli
} // namespace vdbmatch
