/// @file CliSupport.cc
#include "CliSupport.h"

#include <vdbmatch/geometry/SurfacePieces.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <limits>
#include <sstream>
#include <sys/file.h>
#include <unistd.h>

namespace vdbmatch {
namespace cli {

const char* const PROGRAM = "vdb_match";

void
createOutputDirectory(const std::string& dir)
{
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (!std::filesystem::is_directory(dir)) {
        OPENVDB_THROW(openvdb::IoError, "cannot create the output directory '"
                                            << dir << "'"
                                            << (ec ? ": " + ec.message() : std::string()));
    }
}

std::string
commandLine(int argc, const char* const* argv)
{
    std::string line;
    for (int i = 0; i < argc; ++i) {
        if (i) line += ' ';
        line += argv[i];
    }
    return line;
}

int
parseThreads(const std::string& text)
{
    const int n = parseInt("--threads", text);
    if (n < 0 || n > MAX_THREADS) {
        throw UsageError("--threads must be in 0.." + std::to_string(MAX_THREADS) +
                         " (0: all cores), got " + text);
    }
    return n;
}

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

bool
parseOnOff(const std::string& option, const std::string& text)
{
    if (text != "on" && text != "off")
        throw UsageError(option + " expects 'on' or 'off', got '" + text + "'");
    return text == "on";
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
    // A newline in the text starts a new line (e.g. the paper's name of an option).
    std::string flat = text;
    for (size_t at = flat.find('\n'); at != std::string::npos; at = flat.find('\n', at))
        flat.replace(at, 1, " \x1f ");
    std::istringstream words(flat);
    std::string word;
    bool firstWord = true;
    while (words >> word) {
        if (word == "\x1f") {
            out += "\n" + std::string(HELP_COLUMN, ' ');
            column = HELP_COLUMN;
            firstWord = true;
            continue;
        }
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

////////////////////////////////////////////////////////////////////////////////
// Options (CLI11)

namespace {

/// The spellings of "--output,-o": {"--output", "-o"}.
std::vector<std::string>
splitNames(const std::string& names)
{
    std::vector<std::string> out;
    std::string name;
    std::istringstream in(names);
    while (std::getline(in, name, ','))
        if (!name.empty()) out.push_back(name);
    return out;
}

/// CLI11 lists short names first ("-o,--output"); ours start with the canonical long name.
std::string
cli11Names(const std::string& names)
{
    std::vector<std::string> parts = splitNames(names);
    std::stable_partition(parts.begin(), parts.end(),
                          [](const std::string& n) { return n.size() == 2; });
    std::string out;
    for (const std::string& n : parts)
        out += (out.empty() ? "" : ",") + n;
    return out;
}

/// Levenshtein distance.
std::size_t
editDistance(const std::string& a, const std::string& b)
{
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j)
        row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diagonal = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1])});
            diagonal = up;
        }
    }
    return row[b.size()];
}

/// The help flags every command has, after its own options.
constexpr const char* HELP_GROUP = "Other";

/// The option lines of vdb_match: "  --name METAVAR" then the help text from column 26, wrapped
/// at 100 columns; groups separated by a blank line, in table order.
class HelpFormatter : public CLI::Formatter
{
public:
    std::string make_group(std::string group, bool,
                           std::vector<const CLI::Option*> opts) const override
    {
        std::string s = "\n" + group + ":\n";
        for (const CLI::Option* opt : opts)
            s += make_option(opt, false);
        return s;
    }
    std::string make_option(const CLI::Option* opt, bool) const override
    {
        std::string left;
        for (const std::string& n : opt->get_snames())
            left += (left.empty() ? "-" : ", -") + n;
        for (const std::string& n : opt->get_lnames())
            left += (left.empty() ? "--" : ", --") + n;
        if (!opt->get_type_name().empty()) left += " " + opt->get_type_name();
        return wrapHelp(left, opt->get_description());
    }
    std::string make_help(const CLI::App* app, std::string, CLI::AppFormatMode) const override
    {
        std::string s;
        for (const std::string& group : app->get_groups()) {
            const std::vector<const CLI::Option*> opts =
                app->get_options([&](const CLI::Option* o) {
                    return o->get_group() == group && o->nonpositional();
                });
            if (!group.empty() && !opts.empty()) s += make_group(group, false, opts);
        }
        return s;
    }
};

/// The CLI11 app of one command: every option of @a options (in order, grouped), then -h/--help
/// and --version; positional arguments collected into @a positional; unknown options kept for
/// the caller (allow_extras) so that it can suggest the closest spelling.
void
buildApp(CLI::App& app, const std::vector<BoundOption>& options,
         std::vector<std::string>& positional)
{
    app.set_help_flag();
    app.allow_extras();
    app.formatter(std::make_shared<HelpFormatter>());
    for (const BoundOption& b : options) {
        CLI::Option* opt = nullptr;
        auto apply = b.apply;
        if (b.metavar) {
            opt = app.add_option(
                cli11Names(b.names),
                [apply](const CLI::results_t& values) {
                    for (const std::string& v : values)
                        apply(v);
                    return true;
                },
                b.help);
            // "A.csv B.csv": an option with two values.
            const int values =
                1 + int(std::count(b.metavar, b.metavar + std::strlen(b.metavar), ' '));
            opt->type_name(b.metavar)->type_size(1)->expected(values);
            opt->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
        } else {
            opt = app.add_flag_callback(
                cli11Names(b.names), [apply]() { apply(std::string()); }, b.help);
            opt->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
        }
        opt->group(b.group)->trigger_on_parse();
    }
    app.add_flag_callback(
           "-h,--help", []() { throw HelpRequested{}; }, "print this help and exit")
        ->group(HELP_GROUP)
        ->trigger_on_parse();
    app.add_flag_callback(
           "--version", []() { throw VersionRequested{}; }, "print the version and exit")
        ->group(HELP_GROUP)
        ->trigger_on_parse();
    app.add_option("arguments", positional, "positional arguments")->group("");
}

} // namespace

std::string
canonicalName(const char* name)
{
    const std::string n = name;
    return n.substr(0, n.find(','));
}

std::string
closestSpelling(const std::string& word, const std::vector<std::string>& candidates)
{
    std::string best;
    std::size_t bestDistance = std::string::npos;
    for (const std::string& c : candidates) {
        const std::size_t d = editDistance(word, c);
        if (d < bestDistance) {
            bestDistance = d;
            best = c;
        }
    }
    // A typo: a few edits, fewer than a third of the word (so '--x' does not suggest '--q').
    const std::size_t limit = std::max<std::size_t>(1, std::min<std::size_t>(3, word.size() / 3));
    return bestDistance <= limit ? best : std::string();
}

std::vector<std::string>
parseCommandLine(const std::vector<BoundOption>& options, int argc, const char* const* argv,
                 int first)
{
    CLI::App app;
    std::vector<std::string> positional;
    buildApp(app, options, positional);
    std::vector<std::string> args;
    for (int i = argc - 1; i >= first; --i)
        args.emplace_back(argv[i]); // CLI11 takes them reversed
    try {
        app.parse(args);
    } catch (const CLI::ArgumentMismatch& e) {
        // "--level: 1 required L missing", "Expected exactly 1 arguments to --level, got 0":
        // the option is one of the words.
        const std::string what = e.what();
        std::vector<std::string> words;
        std::string word;
        for (const char c : what + " ") {
            if (c == ' ' || c == ':' || c == ',') {
                if (!word.empty()) words.push_back(word);
                word.clear();
            } else {
                word += c;
            }
        }
        for (const BoundOption& b : options) {
            for (const std::string& n : splitNames(b.names)) {
                if (b.metavar && std::find(words.begin(), words.end(), n) != words.end()) {
                    const bool two = std::strchr(b.metavar, ' ') != nullptr;
                    throw UsageError(canonicalName(b.names.c_str()) +
                                     (two ? " expects two values " : " expects a value ") +
                                     b.metavar);
                }
            }
        }
        throw UsageError(what);
    } catch (const CLI::ConversionError& e) {
        // A flag given a value CLI11 cannot read as true/false ("--quiet=maybe").
        const std::string what = e.what();
        for (const BoundOption& b : options) {
            if (b.metavar) continue;
            for (const std::string& n : splitNames(b.names)) {
                if (what.find(n + " ") != std::string::npos ||
                    what.find(n + "=") != std::string::npos)
                    throw UsageError(n + " takes no value");
            }
        }
        throw UsageError(what);
    } catch (const CLI::ParseError& e) {
        throw UsageError(e.what());
    }
    const std::vector<std::string> extras = app.remaining();
    for (const std::string& extra : extras) {
        if (extra.size() < 2 || extra[0] != '-' || extra == "--") continue;
        const std::string name = extra.substr(0, extra.find('='));
        std::vector<std::string> spellings = {"--help", "--version"};
        for (const BoundOption& b : options) {
            const std::vector<std::string> names = splitNames(b.names);
            spellings.insert(spellings.end(), names.begin(), names.end());
            // A known flag given a value ("--quiet=1") lands here too.
            if (b.metavar == nullptr && std::find(names.begin(), names.end(), name) != names.end())
                throw UsageError(name + " takes no value");
        }
        const std::string suggestion = closestSpelling(name, spellings);
        throw UsageError("unknown option '" + name + "'" +
                         (suggestion.empty() ? std::string(" (see vdb_match --help)")
                                             : " (did you mean " + suggestion + "?)"));
    }
    // Arguments CLI11 could not place (none expected: every non-option is positional).
    for (const std::string& extra : extras)
        if (extra != "--") positional.push_back(extra);
    return positional;
}

void
assignInputs(const std::vector<std::string>& positional, std::string& source, std::string& target,
             const std::string& what)
{
    const std::size_t needed = std::size_t(source.empty()) + std::size_t(target.empty());
    if (positional.size() != needed) {
        throw UsageError(what + ", got " + std::to_string(positional.size()) + " file argument(s)" +
                         (needed < 2 ? " besides --source/--target" : std::string()) +
                         " (see vdb_match --help)");
    }
    std::size_t next = 0;
    if (source.empty()) source = positional[next++];
    if (target.empty()) target = positional[next++];
}

Shape
readInputShape(const std::string& path, const std::string& gridName, std::optional<double> isoValue)
{
    if (!gridName.empty() && isShapeFile(path) && !isLevelSetFile(path)) {
        throw UsageError("--grid applies to .vdb inputs, not to '" + path + "'");
    }
    if (!isLevelSetFile(path)) isoValue.reset(); // meshes and polylines are surfaces already
    return readShape(path, gridName, isoValue);
}

void
checkIsoValueInputs(const std::optional<double>& isoValue, const std::string& source,
                    const std::string& target)
{
    if (isoValue && !isLevelSetFile(source) && !isLevelSetFile(target)) {
        throw UsageError("--iso-value applies to .vdb densities (fog volumes), and neither input "
                         "is a .vdb file");
    }
}

std::string
renderOptionHelp(const std::vector<BoundOption>& options)
{
    CLI::App app;
    std::vector<std::string> positional;
    buildApp(app, options, positional);
    return app.help();
}

namespace {

std::atomic<bool> sInterrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");
/// Whether a second signal terminates at once (the CLI) or only raises the flag again (an
/// embedding, RunHooks).
std::atomic<bool> sSecondSignalTerminates{true};
const RunHooks* sHooks = nullptr;

extern "C" void
onSignal(int sig)
{
    sInterrupted.store(true);
    if (sSecondSignalTerminates.load()) std::signal(sig, SIG_DFL);
}

} // namespace

HooksScope::HooksScope(const RunHooks* hooks) : mPrevious(sHooks)
{
    sHooks = hooks;
}

HooksScope::~HooksScope()
{
    sHooks = mPrevious;
}

const RunHooks*
currentHooks()
{
    return sHooks;
}

SignalScope::SignalScope() : mInstalled(!sHooks || sHooks->handleSignals)
{
    sInterrupted.store(false);
    if (!mInstalled) return;
    sSecondSignalTerminates.store(sHooks == nullptr);
    mInt = std::signal(SIGINT, onSignal);
    mTerm = std::signal(SIGTERM, onSignal);
}

SignalScope::~SignalScope()
{
    if (!mInstalled) return;
    std::signal(SIGINT, mInt);
    std::signal(SIGTERM, mTerm);
}

bool
wasSignalled()
{
    return sInterrupted.load() || (sHooks && sHooks->cancel && sHooks->cancel->load());
}

void
checkInterrupted()
{
    if (wasSignalled()) throw Interrupted{};
}

std::string
duration(double seconds)
{
    if (!std::isfinite(seconds) || seconds < 0) return "?";
    if (seconds < 60) return fixed("%.1fs", seconds);
    const int s = int(std::lround(seconds));
    if (s < 3600) return std::to_string(s / 60) + "m" + fixed("%02.0fs", double(s % 60));
    return std::to_string(s / 3600) + "h" + fixed("%02.0fm", double((s % 3600) / 60));
}

OutputLock::OutputLock(const std::string& dir)
{
    const std::string path = (std::filesystem::path(dir) / ".vdb_match.lock").string();
    mFd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (mFd < 0) {
        OPENVDB_THROW(openvdb::IoError, "cannot create '" << path << "': " << std::strerror(errno));
    }
    if (::flock(mFd, LOCK_EX | LOCK_NB) != 0) {
        ::close(mFd);
        OPENVDB_THROW(openvdb::IoError, "another vdb_match is writing to '"
                                            << dir << "'; wait for it or choose another -o");
    }
}

OutputLock::~OutputLock()
{
    ::close(mFd);
}

double
secondsSince(Clock::time_point t0)
{
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

Json
jsonVec(const openvdb::Vec3d& v)
{
    return Json::array({v[0], v[1], v[2]});
}

Json
energyParametersJson(const EnergyParameters& p)
{
    return Json{{"cMatch", p.cMatch},
                {"cMem", p.cMem},
                {"cBend", p.cBend},
                {"cVol", p.cVol},
                {"q", p.q},
                {"theta", p.theta},
                {"tau", p.tau},
                {"sigmaFactor", p.sigmaFactor},
                {"membraneSaturation", p.membraneSaturation}};
}

std::string
dumpJson(const Json& j)
{
    // Paths need not be UTF-8: replace invalid bytes instead of throwing.
    return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::string
fixed(const char* format, double x)
{
    char buf[64];
    std::snprintf(buf, sizeof(buf), format, x);
    return buf;
}

namespace {

SmallPieces
piecesOf(const Shape& in)
{
    return in.dim == 2 ? smallPieces(in.get<2>()) : smallPieces(in.get<3>());
}

} // namespace

Json
shapeJson(const Shape& in)
{
    const SmallPieces pieces = piecesOf(in);
    Json j{{"path", in.path},
           {"format", in.format},
           {"grid", in.grid},
           {"vertices", in.dim == 2 ? in.curve.points.size() : in.surface.points.size()},
           {"elements", in.dim == 2 ? in.curve.elements.size() : in.surface.elements.size()}};
    if (in.isoValue) j["isoValue"] = *in.isoValue;
    j["pieces"] = pieces.pieces;
    j["smallPieces"] = Json{{"count", pieces.small},
                            {"vertices", pieces.smallVertices},
                            {"share", pieces.smallShare},
                            {"farthest", pieces.farthest}};
    return j;
}

std::string
smallPiecesWarning(const Shape& in, const char* role)
{
    const SmallPieces p = piecesOf(in);
    if (p.small == 0) return {};
    const openvdb::BBoxd box = in.dim == 2 ? boundingBox(in.get<2>()) : boundingBox(in.get<3>());
    const std::string where = p.farthest > 0
                                  ? "up to " + fixed("%.3g", p.farthest) + " world units (" +
                                        fixed("%.1f", 100 * p.farthest / box.extents().length()) +
                                        "% of its box diagonal) away from the largest"
                                  : "within the largest piece's box";
    return std::string("the ") + role + " has " + std::to_string(p.pieces) + " pieces, " +
           std::to_string(p.small) + " of them small (" + std::to_string(p.smallVertices) +
           " vertices, " + fixed("%.2f", 100 * p.smallShare) + "% of its " +
           (in.dim == 3 ? "area" : "length") + "), " + where +
           ": scan debris or an outlier cluster? The match pulls the other shape towards it" +
           (p.farthest > 0 ? " and it widens the unit box" : "") +
           "; remove it if it is not part of the shape";
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

} // namespace cli
} // namespace vdbmatch
