/// @file Cli.cc
/// @brief Command dispatch and the help text of vdb_match.
#include "Cli.h"

#include "CliSupport.h"

#include <openvdb/openvdb.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <new>
#include <ostream>
#include <sstream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

/// One command of vdb_match: its usage line, what it does, and its option lines.
struct CommandInfo
{
    const char* name;
    const char* usage;
    const char* description;
    std::string (*options)();
};

const std::vector<CommandInfo>&
commands()
{
    static const std::vector<CommandInfo> table = {
        {"match", "[match] SOURCE TARGET -o OUTDIR",
         "compute the deformation phi matching SOURCE (M1) onto TARGET (M2) with the multiscale "
         "descent of the paper; writes OUTDIR/deformation.vdb, inverse.vdb, jacobian.vdb, "
         "deformed.vdb, deformed.obj and report.json. Inputs: level sets (.vdb; a "
         "one-voxel-thick slice is a 2D shape), meshes (.obj, .ply, .stl), closed 2D polylines "
         "(.polyline, .txt)",
         &matchOptionHelp},
        {"energy", "energy SOURCE TARGET",
         "read both shapes as match does (level sets, one-voxel-thick slices as 2D shapes, "
         "meshes, polylines), place them in the unit box, build their distance fields at --level "
         "as match does at that level, and print the terms of the matching energy of the "
         "identity deformation (phi = Id) on the dense lattice of that level",
         &energyOptionHelp},
        {"consistency", "consistency PHI.vdb PSI.vdb --source M1 --target M2",
         "measure a pair of deformations of M1 -> M2 (PHI) and M2 -> M1 (PSI), as the paper's "
         "tab:inverseError: |psi(phi(x)) - x| and |phi(psi(y)) - y| over the domain (L2 as rms, "
         "Linf) and over the shapes' vertices (mean, max), |phi^-1(phi(x)) - x| and "
         "|psi(y) - phi^-1(y)| with the exact inverse, the residuals |d2(phi(x))| on M1 and "
         "|d1(psi(y))| on M2, det D phi and det D psi; world units and fractions of the domain "
         "size",
         &consistencyOptionHelp},
        {"slice", "slice PHI.vdb --source M1 --target M2 -o OUT.exr",
         "sample an axis-aligned plane of the domain into OUT.exr (channels d1, d2, "
         "displacement, det, residual and, with --inverse, inverse_error; world units) and "
         "write one PNG preview per channel, OUT.<channel>.png",
         &sliceOptionHelp},
        {"texture", "texture PHI.vdb --source M1 -o OUTDIR",
         "paint a pattern on M1 and carry it by phi (and psi o phi with --inverse PSI.vdb): "
         "coloured PLY meshes (3D) or OBJ curves and deformed grid lines (2D), PNG pictures and "
         "summary.png",
         &textureOptionHelp},
        {"apply", "apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse]",
         "carry a mesh (.obj .ply .stl: vertices and normals moved, everything else kept), a "
         "point file (.csv .xyz .txt), 2D curves (.polyline) or the grids of a .vdb file (level "
         "sets rebuilt around the moved surface, other grids resampled) by phi, or by its exact "
         "inverse with --inverse",
         &applyOptionHelp},
        {"batch",
         "batch (--all-pairs FILES... | --template T FILES... | --sequence PATTERN --frames A-B) "
         "-o OUTDIR [-- MATCH OPTIONS]; batch status OUTDIR; batch collect OUTDIR",
         "run many matches as the jobs of one plan (every pair of FILES, T to each FILE, or frame "
         "k to k+1 of a sequence), each an ordinary match with the MATCH OPTIONS after -- in "
         "OUTDIR/jobs/SOURCE--TARGET, on this machine in child processes (one per core, one "
         "thread each); OUTDIR/plan.json records the jobs and their states, and the same "
         "command again resumes (finished jobs with whole outputs are skipped, the others "
         "redone); a failing job does not stop the others. 'batch status' prints the jobs, "
         "'batch collect' writes OUTDIR/distances.csv and summary.json (docs/batch.md)",
         &batchOptionHelp},
    };
    return table;
}

const CommandInfo*
findCommand(const std::string& name)
{
    for (const CommandInfo& c : commands())
        if (name == c.name) return &c;
    return nullptr;
}

/// @a text wrapped at 100 columns, no indent.
std::string
wrapParagraph(const std::string& text)
{
    constexpr std::size_t WIDTH = 100;
    std::string out, line, word;
    std::istringstream words(text);
    while (words >> word) {
        if (!line.empty() && line.size() + 1 + word.size() > WIDTH) {
            out += line + "\n";
            line.clear();
        }
        line += (line.empty() ? "" : " ") + word;
    }
    return out + line + "\n";
}

std::string
exitCodeHelp()
{
    std::string s = "\nExit codes:\n";
    s += wrapHelp("0", "success");
    s += wrapHelp("1", "usage error: unknown command or option, missing argument, malformed "
                       "number, contradictory options, --threads outside 0..1024");
    s += wrapHelp("2", "I/O error: missing or unreadable file, output directory not writable");
    s += wrapHelp("3", "invalid input: not a level set, several grids and no --grid, NaN or "
                       "inf, empty grid, non-uniform voxels, open surface, 2D/3D mismatch, "
                       "shapes that do not fit the domain, not a deformation grid, a slice "
                       "position outside the domain, parameter out of range (levels: finest 9 "
                       "in 3D, 12 in 2D), an --init result of other inputs or that folds");
    s += wrapHelp("4", "match --strict: the finest level did not converge (outputs written)");
    s += wrapHelp("5", "interrupted (SIGINT, SIGTERM); match writes what was computed, marked "
                       "as interrupted");
    s += wrapHelp("6", "batch: every job ran but some failed (each listed with its error; "
                       "running the command again redoes them)");
    s += "\nErrors are printed to stderr as one line 'vdb_match: error: ...'.\n";
    return s;
}

} // namespace

std::string
helpText()
{
    std::string s;
    s += std::string(PROGRAM) + " " + VDBMATCH_VERSION +
         ": smooth invertible matching of closed surfaces (3D) and curves (2D)\n\n";
    s += "Usage:\n";
    s += "  vdb_match SOURCE TARGET -o OUTDIR [options]   (same as: vdb_match match ...)\n";
    for (const CommandInfo& c : commands()) {
        if (std::string(c.name) != "match")
            s += "  vdb_match " + std::string(c.usage) + " [options]\n";
    }
    s += "  vdb_match COMMAND --help                      (the options of one command)\n";
    s += "  vdb_match --help | --version\n\n";
    s += "Commands:\n";
    for (const CommandInfo& c : commands())
        s += wrapHelp(c.usage, c.description);
    s += "\nOther:\n";
    s += wrapHelp("-h, --help", "print this help and exit");
    s += wrapHelp("--version", "print the version and exit");
    s += exitCodeHelp();
    return s;
}

std::string
commandHelpText(const std::string& name)
{
    if (name == "apply") return applyHelpText();
    const CommandInfo* c = findCommand(name);
    if (!c) return helpText();
    std::string s = "Usage: vdb_match " + std::string(c->usage) + " [options]\n\n";
    s += wrapParagraph(std::string(c->description) + ".");
    s += "\nOptions, as --name VALUE or --name=VALUE.\n";
    s += c->options();
    s += exitCodeHelp();
    s += "See docs/cli.md; 'vdb_match --help' lists every command.\n";
    return s;
}

namespace {

std::string
versionText()
{
    return std::string(PROGRAM) + " " + VDBMATCH_VERSION + " (OpenVDB " +
           openvdb::getLibraryVersionString() + ")\n";
}

/// The command a word names, or an error for a word that is neither a command nor a file:
/// a mistyped command, with the closest command name.
/// @throw UsageError
void
rejectUnknownCommand(const std::string& word)
{
    if (word.empty() || word[0] == '-' || word.find_first_of("./\\") != std::string::npos) return;
    std::error_code ec;
    if (std::filesystem::exists(word, ec)) return; // a file without extension
    std::vector<std::string> names;
    std::string list;
    for (const CommandInfo& c : commands()) {
        names.push_back(c.name);
        list += std::string(list.empty() ? "" : ", ") + c.name;
    }
    const std::string suggestion = closestSpelling(word, names);
    throw UsageError("unknown command '" + word + "' (" +
                     (suggestion.empty() ? std::string() : "did you mean " + suggestion + "? ") +
                     "commands: " + list + "; vdb_match --help)");
}

} // namespace

std::vector<OptionDescription>
commandOptions(const std::string& command)
{
    if (command == "match") return matchOptionDescriptions();
    if (command == "energy") return energyOptionDescriptions();
    if (command == "consistency") return consistencyOptionDescriptions();
    if (command == "slice") return sliceOptionDescriptions();
    if (command == "texture") return textureOptionDescriptions();
    if (command == "apply") return applyOptionDescriptions();
    if (command == "batch") return batchOptionDescriptions();
    return {};
}

int
run(int argc, const char* const* argv, std::ostream& out, std::ostream& err, const RunHooks& hooks)
{
    const HooksScope scope(&hooks);
    return run(argc, argv, out, err);
}

int
run(int argc, const char* const* argv, std::ostream& out, std::ostream& err)
{
    auto fail = [&](int code, const std::string& message) {
        err << PROGRAM << ": error: " << oneLine(message) << std::endl;
        return code;
    };
    std::string command = "match";
    try {
        if (argc < 2) throw UsageError("missing arguments (see vdb_match --help)");
        // The program's own options, up to the first argument that is not one of them: the
        // command word, or (implicit match) a file or an option of match.
        CLI::App top(PROGRAM);
        top.set_help_flag();
        bool help = false, version = false;
        top.add_flag("-h,--help", help);
        top.add_flag("--version", version);
        top.prefix_command();
        std::vector<std::string> args;
        for (int i = argc - 1; i >= 1; --i)
            args.emplace_back(argv[i]);
        try {
            top.parse(args);
        } catch (const CLI::ParseError& e) {
            throw UsageError(e.what());
        }
        const std::vector<std::string> rest = top.remaining();
        if (help || (!rest.empty() && rest[0] == "help")) {
            out << helpText();
            return EXIT_OK;
        }
        if (version) {
            out << versionText();
            return EXIT_OK;
        }
        if (rest.empty()) throw UsageError("missing arguments (see vdb_match --help)");
        const int restStart = argc - int(rest.size());
        const bool explicitCommand = findCommand(rest[0]) != nullptr;
        if (explicitCommand) {
            command = rest[0];
        } else {
            rejectUnknownCommand(rest[0]);
        }
        const int first = explicitCommand ? restStart + 1 : restStart;
        try {
            if (command == "energy") return runEnergyCommand(argc, argv, first, out, err);
            if (command == "consistency") return runConsistencyCommand(argc, argv, first, out, err);
            if (command == "slice") return runSliceCommand(argc, argv, first, out, err);
            if (command == "texture") return runTextureCommand(argc, argv, first, out, err);
            if (command == "apply") return runApplyCommand(argc, argv, first, out, err);
            if (command == "batch") return runBatchCommand(argc, argv, first, out, err);
            return runMatchCommand(argc, argv, first, out, err);
        } catch (const HelpRequested&) {
            out << commandHelpText(command);
            return EXIT_OK;
        } catch (const VersionRequested&) {
            out << versionText();
            return EXIT_OK;
        }
    } catch (const UsageError& e) {
        return fail(EXIT_USAGE, e.what());
    } catch (const Interrupted&) {
        return fail(EXIT_INTERRUPTED, "interrupted");
    } catch (const openvdb::IoError& e) {
        return fail(EXIT_IO, e.what());
    } catch (const openvdb::Exception& e) {
        return fail(EXIT_INVALID_INPUT, e.what());
    } catch (const std::bad_alloc&) {
        return fail(EXIT_INVALID_INPUT, "out of memory (try a lower --max-level)");
    } catch (const std::exception& e) {
        return fail(EXIT_INVALID_INPUT, e.what());
    }
}

} // namespace cli
} // namespace vdbmatch
