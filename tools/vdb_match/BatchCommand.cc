/// @file BatchCommand.cc
/// @brief `vdb_match batch`: many matches as jobs of one plan. A plan is all pairs of a
///        collection, a template matched to each shape, or the consecutive frames of a sequence;
///        each job is an ordinary `match` (same options, same outputs) in OUTDIR/jobs/NAME, run
///        by a child vdb_match process on this machine. OUTDIR/plan.json records the jobs and
///        their states, so that running the same command again resumes; `batch status` prints
///        it and `batch collect` writes distances.csv and summary.json (docs/batch.md).
#include "CliSupport.h"

#include <vdbmatch/eval/DistanceMatrix.h>
#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/render/MatrixPlots.h>

#include <openvdb/io/File.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <sys/resource.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace vdbmatch {
namespace cli {

namespace {

namespace fs = std::filesystem;

struct BatchCliOptions
{
    bool allPairs = false;
    std::string templateShape;
    std::string sequence;
    std::string frames;
    bool bothDirections = false;
    bool warmStart = false; ///< sequence: job k starts from job k-1's map
    std::string outDir;
    int jobs = 0;          ///< concurrent jobs, 0: automatic
    int threadsPerJob = 0; ///< 0: automatic
    bool quiet = false;
    std::string executor = "local"; ///< local or slurm
    int arrayThrottle = 0;          ///< slurm: tasks at a time (0: no limit)
    int memoryPerTaskMB = 0;        ///< slurm: 0: from the finest level
    bool wait = false;              ///< slurm: wait for the array to end
};

std::vector<Option<BatchCliOptions>>
batchOptionTable()
{
    using O = BatchCliOptions;
    // clang-format off
    return {
        {"--all-pairs", nullptr, "Plan",
         "match every pair of the FILES (i < j: one direction; the symmetric energy makes it "
         "enough for a distance)",
         [](O& o, const std::string&) { o.allPairs = true; }},
        {"--both-directions", nullptr, "Plan",
         "with --all-pairs, also match j -> i (for |psi o phi - Id| in batch collect)",
         [](O& o, const std::string&) { o.bothDirections = true; }},
        {"--template", "T", "Plan", "match the shape T to each of the FILES",
         [](O& o, const std::string& v) { o.templateShape = v; }},
        {"--sequence", "PATTERN", "Plan",
         "frames of a sequence: shape.####.vdb (Blender), shape.$F4.vdb (Houdini) or "
         "shape.%04d.vdb; frame k is matched to frame k+1",
         [](O& o, const std::string& v) { o.sequence = v; }},
        {"--frames", "A-B", "Plan", "the frame range of --sequence, e.g. 1-240",
         [](O& o, const std::string& v) { o.frames = v; }},
        {"--warm-start", nullptr, "Plan",
         "with --sequence: start each pair k -> k+1 from the map of k-1 -> k (match "
         "--warm-start, from level 6); the jobs then run one after the other, "
         "each with every core (docs/batch.md: when it helps)",
         [](O& o, const std::string&) { o.warmStart = true; }},
        {"--output,-o", "OUTDIR", "Output",
         "batch directory: plan.json and jobs/NAME/ (the outputs of each match) (required)",
         [](O& o, const std::string& v) { o.outDir = v; }},
        {"--jobs", "N", "Execution",
         "concurrent jobs (default: one per core, see --threads-per-job)",
         [](O& o, const std::string& v) { o.jobs = parseInt("--jobs", v); }},
        {"--threads-per-job", "N", "Execution",
         "threads of each job (default: the cores divided among the jobs running, at least 1)",
         [](O& o, const std::string& v) { o.threadsPerJob = parseInt("--threads-per-job", v); }},
        {"--executor", "NAME", "Execution",
         "local (default: child processes on this machine) or slurm (a job array submitted "
         "with sbatch; follow it with batch status, or --wait)",
         [](O& o, const std::string& v) {
             if (v != "local" && v != "slurm")
                 throw UsageError("--executor: expected local or slurm, got '" + v + "'");
             o.executor = v;
         }},
        {"--array-throttle", "N", "Execution", "slurm: at most N array tasks at a time (default: no limit)",
         [](O& o, const std::string& v) { o.arrayThrottle = parseInt("--array-throttle", v); }},
        {"--memory-per-task", "MB", "Execution",
         "slurm: memory per task (default: from the finest level: 1 GB up to level 7, 2 GB at "
         "8, 8 GB at 9)",
         [](O& o, const std::string& v) { o.memoryPerTaskMB = parseInt("--memory-per-task", v); }},
        {"--wait", nullptr, "Execution",
         "slurm: wait until every task has ended, then report as the local executor does",
         [](O& o, const std::string&) { o.wait = true; }},
        {"--quiet", nullptr, "Execution", "no progress on stderr (errors are still printed)",
         [](O& o, const std::string&) { o.quiet = true; }},
    };
    // clang-format on
}

/// One job of a plan.
struct Job
{
    std::string name;
    std::string source, target;    ///< absolute paths
    std::string state = "pending"; ///< pending, done, failed, interrupted
    int warmFrom = -1;             ///< warm-start plans: the job whose map starts this one, or -1
    bool warmStarted = false;      ///< it did start from that map (false: its job had failed)
    int exitCode = -1;
    std::string error;
    double seconds = 0;
    double peakMemoryMB = 0;
};

struct Plan
{
    std::string kind;       ///< all-pairs, template, sequence
    int firstFrame = 0;     ///< sequence: the frame number of inputs[0]
    bool warmStart = false; ///< sequence: job k starts from job k-1's map (a chain)
    std::string executor = "local";
    std::string slurmJobId;      ///< slurm: the array job of the last submission
    std::vector<int> slurmTasks; ///< slurm: the jobs submitted (array index = job index)
    std::vector<std::string> inputs;
    std::vector<std::string> matchArguments;
    std::vector<Job> jobs;
};

std::string
absolutePath(const std::string& p)
{
    std::error_code ec;
    const fs::path a = fs::absolute(p, ec);
    return (ec ? fs::path(p) : a.lexically_normal()).string();
}

/// The name of a shape in job names: its file name without the extension.
std::string
stemOf(const std::string& path)
{
    return fs::path(path).stem().string();
}

void
requireReadable(const std::string& path, const std::string& what)
{
    std::ifstream f(path, std::ios::binary);
    if (!f) {
        OPENVDB_THROW(openvdb::IoError, what << " '" << path << "': " << std::strerror(errno));
    }
}

/// The first and last frame of --frames A-B.
std::pair<int, int>
frameRange(const std::string& range)
{
    const auto dash = range.find('-', 1);
    if (dash == std::string::npos) throw UsageError("--frames: expected A-B, got '" + range + "'");
    const int a = parseInt("--frames", range.substr(0, dash));
    const int b = parseInt("--frames", range.substr(dash + 1));
    if (b <= a) throw UsageError("--frames: " + range + " needs at least two frames (A < B)");
    return {a, b};
}

/// The frame files of a sequence pattern: #### (as many digits as #), $F4 or %04d.
std::vector<std::string>
sequenceFiles(const std::string& pattern, const std::string& range)
{
    const auto [a, b] = frameRange(range);
    std::string prefix, suffix;
    int width = 0;
    if (auto p = pattern.find('#'); p != std::string::npos) {
        auto q = pattern.find_first_not_of('#', p);
        if (q == std::string::npos) q = pattern.size();
        prefix = pattern.substr(0, p), suffix = pattern.substr(q), width = int(q - p);
    } else if (auto f = pattern.find("$F"); f != std::string::npos) {
        std::size_t q = f + 2;
        while (q < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[q])))
            ++q;
        width = q > f + 2 ? std::stoi(pattern.substr(f + 2, q - f - 2)) : 1;
        prefix = pattern.substr(0, f), suffix = pattern.substr(q);
    } else if (auto d = pattern.find('%'); d != std::string::npos) {
        std::size_t q = d + 1;
        while (q < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[q])))
            ++q;
        if (q >= pattern.size() || pattern[q] != 'd')
            throw UsageError("--sequence: unsupported pattern '" + pattern + "'");
        const std::string digits = pattern.substr(d + 1, q - d - 1);
        width = digits.empty() ? 1 : std::stoi(digits);
        prefix = pattern.substr(0, d), suffix = pattern.substr(q + 1);
    } else {
        throw UsageError("--sequence: '" + pattern +
                         "' has no frame number (use ####, $F4 or %04d)");
    }
    std::vector<std::string> files;
    for (int k = a; k <= b; ++k) {
        std::string n = std::to_string(k);
        if (int(n.size()) < width) n.insert(0, std::size_t(width) - n.size(), '0');
        const std::string file = prefix + n + suffix;
        std::error_code ec;
        if (!fs::exists(file, ec)) {
            OPENVDB_THROW(openvdb::IoError,
                          "frame " << k << " of the sequence is missing: '" << file << "'");
        }
        files.push_back(file);
    }
    return files;
}

Plan
makePlan(const BatchCliOptions& o, const std::vector<std::string>& files,
         const std::vector<std::string>& matchArgs)
{
    const int kinds = int(o.allPairs) + int(!o.templateShape.empty()) + int(!o.sequence.empty());
    if (kinds != 1)
        throw UsageError(
            "batch: give exactly one of --all-pairs, --template T, --sequence PATTERN");
    if (o.bothDirections && !o.allPairs)
        throw UsageError("--both-directions goes with --all-pairs");
    if (o.warmStart && o.sequence.empty()) throw UsageError("--warm-start goes with --sequence");
    Plan plan;
    plan.matchArguments = matchArgs;
    std::vector<std::string> shapes;
    if (!o.sequence.empty()) {
        if (!files.empty()) throw UsageError("--sequence takes no FILES");
        if (o.frames.empty()) throw UsageError("--sequence needs --frames A-B");
        plan.kind = "sequence";
        shapes = sequenceFiles(o.sequence, o.frames);
        plan.firstFrame = frameRange(o.frames).first;
    } else {
        if (!o.frames.empty()) throw UsageError("--frames goes with --sequence");
        plan.kind = o.allPairs ? "all-pairs" : "template";
        if (!o.templateShape.empty()) shapes.push_back(o.templateShape);
        shapes.insert(shapes.end(), files.begin(), files.end());
        if (shapes.size() < 2) {
            throw UsageError(o.allPairs ? "--all-pairs needs at least two FILES"
                                        : "--template T needs at least one FILE");
        }
    }
    // Names: file names without extension, unique.
    std::map<std::string, std::string> byName;
    for (const std::string& s : shapes) {
        requireReadable(s, "cannot read the shape");
        const std::string n = stemOf(s);
        auto [it, fresh] = byName.emplace(n, s);
        if (!fresh && absolutePath(it->second) != absolutePath(s)) {
            throw UsageError("duplicated names: '" + it->second + "' and '" + s +
                             "' would both be called '" + n + "' in the job names; rename one");
        }
        plan.inputs.push_back(absolutePath(s));
    }
    auto add = [&](std::size_t i, std::size_t j) {
        Job job;
        job.name = stemOf(plan.inputs[i]) + "--" + stemOf(plan.inputs[j]);
        job.source = plan.inputs[i];
        job.target = plan.inputs[j];
        plan.jobs.push_back(job);
    };
    const std::size_t n = plan.inputs.size();
    if (plan.kind == "all-pairs") {
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t j = i + 1; j < n; ++j) {
                add(i, j);
                if (o.bothDirections) add(j, i);
            }
    } else if (plan.kind == "template") {
        for (std::size_t j = 1; j < n; ++j)
            if (plan.inputs[j] != plan.inputs[0]) add(0, j);
    } else {
        for (std::size_t k = 0; k + 1 < n; ++k) {
            add(k, k + 1);
            if (o.warmStart && k > 0) plan.jobs.back().warmFrom = int(k) - 1;
        }
        plan.warmStart = o.warmStart;
    }
    std::set<std::string> names;
    for (const Job& j : plan.jobs)
        if (!names.insert(j.name).second)
            throw UsageError("duplicated job name '" + j.name + "' (a shape listed twice?)");
    return plan;
}

Json
planJson(const Plan& p)
{
    Json jobs = Json::array();
    for (const Job& j : p.jobs) {
        jobs.push_back(Json{{"name", j.name},
                            {"source", j.source},
                            {"target", j.target},
                            {"directory", "jobs/" + j.name},
                            {"state", j.state},
                            {"warmStartFrom", j.warmFrom >= 0 ? Json(j.warmFrom) : Json()},
                            {"warmStarted", j.warmStarted},
                            {"exitCode", j.exitCode},
                            {"error", j.error},
                            {"seconds", j.seconds},
                            {"peakMemoryMB", j.peakMemoryMB}});
    }
    Json plan{{"vdbmatch", VDBMATCH_VERSION}, {"plan", p.kind}};
    if (p.kind == "sequence") {
        plan["firstFrame"] = p.firstFrame;
        plan["warmStart"] = p.warmStart;
    }
    plan["inputs"] = p.inputs;
    plan["matchArguments"] = p.matchArguments;
    plan["executor"] = p.executor;
    if (p.executor == "slurm")
        plan["slurm"] = Json{{"jobId", p.slurmJobId}, {"jobs", p.slurmTasks}};
    plan["jobs"] = jobs;
    return plan;
}

void
writePlan(const std::string& outDir, const Plan& p)
{
    const std::string text = dumpJson(planJson(p));
    writeFileAtomically((fs::path(outDir) / "plan.json").string(),
                        [&](std::ostream& os) { os << text; });
}

Plan
readPlan(const std::string& outDir)
{
    const std::string path = (fs::path(outDir) / "plan.json").string();
    std::ifstream f(path);
    if (!f) OPENVDB_THROW(openvdb::IoError, "no batch in '" << outDir << "' (no plan.json)");
    Json j;
    try {
        j = Json::parse(f);
        Plan p;
        p.kind = j.at("plan").get<std::string>();
        p.firstFrame = j.value("firstFrame", 0);
        p.warmStart = j.value("warmStart", false);
        p.executor = j.value("executor", std::string("local"));
        if (j.contains("slurm")) {
            p.slurmJobId = j["slurm"].value("jobId", std::string());
            p.slurmTasks = j["slurm"].value("jobs", std::vector<int>());
        }
        p.inputs = j.at("inputs").get<std::vector<std::string>>();
        p.matchArguments = j.at("matchArguments").get<std::vector<std::string>>();
        for (const Json& e : j.at("jobs")) {
            Job job;
            job.name = e.at("name").get<std::string>();
            job.source = e.at("source").get<std::string>();
            job.target = e.at("target").get<std::string>();
            job.state = e.at("state").get<std::string>();
            if (e.contains("warmStartFrom") && e["warmStartFrom"].is_number_integer())
                job.warmFrom = e["warmStartFrom"].get<int>();
            job.warmStarted = e.value("warmStarted", false);
            job.exitCode = e.value("exitCode", -1);
            job.error = e.value("error", std::string());
            job.seconds = e.value("seconds", 0.0);
            job.peakMemoryMB = e.value("peakMemoryMB", 0.0);
            p.jobs.push_back(job);
        }
        return p;
    } catch (const Json::exception& e) {
        OPENVDB_THROW(openvdb::ValueError, "'" << path << "' is not a batch plan: " << e.what());
    }
}

std::string
jobDir(const std::string& outDir, const std::string& name)
{
    return (fs::path(outDir) / "jobs" / name).string();
}

std::string
jobDir(const std::string& outDir, const Job& j)
{
    return jobDir(outDir, j.name);
}

/// A finished job's outputs are there and whole: report.json of a run that was not
/// interrupted, and deformation.vdb with its displacement grid.
bool
outputsVerified(const std::string& dir, std::string* why = nullptr)
{
    auto fail = [&](const std::string& w) {
        if (why) *why = w;
        return false;
    };
    std::ifstream f(fs::path(dir) / "report.json");
    if (!f) return fail("no report.json");
    try {
        const Json r = Json::parse(f);
        const std::string status = r.at("status").get<std::string>();
        if (status != "converged" && status != "not converged")
            return fail("report.json says " + status);
    } catch (const Json::exception&) {
        return fail("report.json is not valid JSON");
    }
    try {
        openvdb::io::File file((fs::path(dir) / "deformation.vdb").string());
        file.open(false);
        const bool has = file.hasGrid("displacement");
        file.close();
        if (!has) return fail("deformation.vdb has no displacement grid");
    } catch (const openvdb::Exception& e) {
        return fail(std::string("deformation.vdb: ") + e.what());
    }
    return true;
}

/// The last "error:" line of a job's log, or "".
std::string
lastErrorLine(const std::string& logPath)
{
    std::ifstream f(logPath);
    std::string line, last;
    while (std::getline(f, line))
        if (line.find("error:") != std::string::npos) last = line;
    const std::string prefix = std::string(PROGRAM) + ": error: ";
    if (last.rfind(prefix, 0) == 0) last = last.substr(prefix.size());
    return last;
}

/// Whether a job's report says it started from a warm start (match --warm-start, and the start
/// did not fold, which would have made it fall back to the identity).
bool
startedWarm(const Json& report)
{
    if (!report.contains("init") || !report["init"].is_object()) return false;
    const Json& init = report["init"];
    return init.value("kind", std::string()) == "warm-start" && init.value("used", true);
}

bool
startedWarm(const std::string& dir)
{
    std::ifstream f(fs::path(dir) / "report.json");
    try {
        return startedWarm(Json::parse(f));
    } catch (const Json::exception&) {
        return false;
    }
}

/// This program, to start the jobs with.
std::string
selfExecutable()
{
    std::error_code ec;
    const fs::path p = fs::read_symlink("/proc/self/exe", ec);
    if (ec)
        OPENVDB_THROW(openvdb::IoError, "cannot find the vdb_match executable: " << ec.message());
    return p.string();
}

struct Child
{
    pid_t pid = -1;
    std::size_t job = 0;
    Clock::time_point start;
};

/// Starts `vdb_match match SOURCE TARGET -o DIR --quiet --threads T [--warm-start W] ARGS...`,
/// output to DIR/log.txt.
pid_t
startJob(const std::string& exe, const std::string& outDir, const Job& job,
         const std::vector<std::string>& matchArgs, int threads, const std::string& warmStart)
{
    const std::string dir = jobDir(outDir, job);
    createOutputDirectory(dir);
    std::vector<std::string> args = {exe,        "match",     job.source,
                                     job.target, "-o",        dir,
                                     "--quiet",  "--threads", std::to_string(threads)};
    if (!warmStart.empty()) args.insert(args.end(), {"--warm-start", warmStart});
    args.insert(args.end(), matchArgs.begin(), matchArgs.end());
    std::vector<char*> argv;
    for (std::string& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);
    const std::string log = (fs::path(dir) / "log.txt").string();
    const pid_t pid = fork();
    if (pid < 0) OPENVDB_THROW(openvdb::IoError, "cannot start a job: " << std::strerror(errno));
    if (pid == 0) {
        // The child: its own output, this program as `match`. Only async-signal-safe calls.
        std::signal(SIGINT, SIG_DFL);
        std::signal(SIGTERM, SIG_DFL);
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, 1);
            dup2(fd, 2);
            close(fd);
        }
        execv(argv[0], argv.data());
        _exit(127);
    }
    return pid;
}

std::string
shellQuote(const std::string& s)
{
    std::string q = "'";
    for (char c : s) {
        if (c == '\'') {
            q += "'\\''";
        } else {
            q += c;
        }
    }
    return q + "'";
}

/// The deformation a job of a warm-start plan starts from (its predecessor's), or "".
std::string
warmStartFile(const std::string& outDir, const Plan& plan, const Job& job)
{
    if (job.warmFrom < 0) return {};
    return absolutePath(
        (fs::path(jobDir(outDir, plan.jobs[std::size_t(job.warmFrom)])) / "deformation.vdb")
            .string());
}

/// The shell line of a job, as in jobs.txt: its folder made, then the match with its output
/// in DIR/log.txt. A job of a warm-start plan starts from @a warmStart when that file is there
/// (its job succeeded), else from the identity.
std::string
jobCommandLine(const std::string& exe, const std::string& outDir, const Job& job,
               const std::vector<std::string>& matchArgs, int threads,
               const std::string& warmStart = {})
{
    const std::string dir = absolutePath(jobDir(outDir, job));
    std::string match = shellQuote(exe) + " match " + shellQuote(job.source) + " " +
                        shellQuote(job.target) + " -o " + shellQuote(dir) + " --quiet --threads " +
                        std::to_string(threads);
    std::string options;
    for (const std::string& a : matchArgs)
        options += " " + shellQuote(a);
    const std::string log = " > " + shellQuote(dir + "/log.txt") + " 2>&1";
    if (warmStart.empty())
        return "mkdir -p " + shellQuote(dir) + " && exec " + match + options + log;
    return "mkdir -p " + shellQuote(dir) + " && if [ -s " + shellQuote(warmStart) +
           " ]; then exec " + match + " --warm-start " + shellQuote(warmStart) + options + log +
           "; else exec " + match + options + log + "; fi";
}

/// OUTDIR/jobs.txt: line k + 1 is the shell command of job k (docs/batch.md).
void
writeJobList(const std::string& outDir, const Plan& plan, const std::string& exe, int threads)
{
    std::string text;
    for (const Job& j : plan.jobs)
        text += jobCommandLine(exe, outDir, j, plan.matchArguments, threads,
                               warmStartFile(outDir, plan, j)) +
                "\n";
    writeFileAtomically((fs::path(outDir) / "jobs.txt").string(),
                        [&](std::ostream& os) { os << text; });
}

/// Runs a shell command; returns its exit status and its output (stdout and stderr).
std::pair<int, std::string>
capture(const std::string& command)
{
    std::string output;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return {-1, std::strerror(errno)};
    char buf[4096];
    std::size_t n;
    while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0)
        output.append(buf, n);
    const int status = pclose(pipe);
    return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::string
firstLine(const std::string& text)
{
    std::string line = text.substr(0, text.find('\n'));
    return line.empty() ? text : line;
}

/// The finest level the match options ask for (--levels A..B, --max-level L; default 8).
int
finestLevel(const std::vector<std::string>& args)
{
    int level = 8;
    for (std::size_t i = 0; i + 1 < args.size(); ++i) {
        if (args[i] == "--levels") {
            const auto dots = args[i + 1].find("..");
            if (dots != std::string::npos) level = std::atoi(args[i + 1].c_str() + dots + 2);
        } else if (args[i] == "--max-level") {
            level = std::atoi(args[i + 1].c_str());
        }
    }
    return level;
}

/// Memory per Slurm task: the peak of one 3D match at its finest level with margin (0.35 GB at
/// 4..7 and 0.75 GB at 4..8 measured, docs/performance.md).
int
defaultMemoryMB(int level)
{
    return level <= 7 ? 1024 : level == 8 ? 2048 : 8192;
}

int
countState(const Plan& p, const std::string& state)
{
    return int(std::count_if(p.jobs.begin(), p.jobs.end(),
                             [&](const Job& j) { return j.state == state; }));
}

int
runPlan(const BatchCliOptions& o, Plan& plan, std::ostream& out, std::ostream& err)
{
    auto say = [&](const std::string& text) {
        if (!o.quiet) err << PROGRAM << ": " << text << std::endl;
    };
    // Jobs whose outputs are there and whole are skipped; the others are (re)done.
    std::vector<std::size_t> todo;
    int skipped = 0;
    for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
        Job& j = plan.jobs[i];
        if (j.state == "done" && outputsVerified(jobDir(o.outDir, j))) {
            ++skipped;
            continue;
        }
        j.state = "pending";
        j.error.clear();
        j.exitCode = -1;
        todo.push_back(i);
    }
    writePlan(o.outDir, plan);
    const int cores = std::max(1, int(std::thread::hardware_concurrency()));
    // One job per core with one thread each: the 1 -> 2 thread speed-up of a match is 1.78-1.86
    // (docs/performance.md), so two 1-thread jobs finish more work per second than one 2-thread
    // job; when fewer jobs than cores are left, each gets the cores left over.
    // A warm-start plan is a chain: each job waits for the one before, so one runs at a time.
    const int concurrency = plan.warmStart ? 1 : o.jobs > 0 ? o.jobs : cores;
    say("batch: " + plan.kind + ", " + std::to_string(plan.jobs.size()) + " jobs (" +
        std::to_string(skipped) + " already done), " + std::to_string(concurrency) +
        " at a time, in " + o.outDir);
    const std::string exe = selfExecutable();
    const Clock::time_point start = Clock::now();
    std::vector<Child> running;
    std::size_t next = 0;
    double finishedSeconds = 0;
    int finished = 0;
    bool stopping = false;
    while (next < todo.size() || !running.empty()) {
        if (wasSignalled() && !stopping) {
            stopping = true;
            say("batch: interrupted; stopping the running jobs (they will be redone)");
            for (const Child& c : running)
                kill(c.pid, SIGTERM);
        }
        while (!stopping && next < todo.size() && int(running.size()) < concurrency) {
            Job& job = plan.jobs[todo[next]];
            // A warm-started job starts from its predecessor's map once that job is done, or
            // from the identity if it failed.
            std::string warm;
            if (job.warmFrom >= 0) {
                const Job& from = plan.jobs[std::size_t(job.warmFrom)];
                if (from.state == "running" || from.state == "pending") break;
                if (from.state == "done") warm = warmStartFile(o.outDir, plan, job);
            }
            job.warmStarted = !warm.empty();
            const std::size_t left = todo.size() - next + running.size();
            const int threads =
                o.threadsPerJob > 0
                    ? o.threadsPerJob
                    : std::max(1,
                               cores / int(std::min<std::size_t>(left, std::size_t(concurrency))));
            Child c;
            c.job = todo[next];
            c.start = Clock::now();
            try {
                c.pid = startJob(exe, o.outDir, job, plan.matchArguments, threads, warm);
            } catch (const openvdb::Exception& e) {
                job.state = "failed";
                job.error = e.what();
                ++next;
                continue;
            }
            job.state = "running";
            running.push_back(c);
            ++next;
            writePlan(o.outDir, plan);
        }
        // Reap finished children.
        bool reaped = false;
        for (std::size_t k = 0; k < running.size();) {
            int status = 0;
            struct rusage ru;
            std::memset(&ru, 0, sizeof(ru));
            const pid_t r = wait4(running[k].pid, &status, WNOHANG, &ru);
            if (r == 0 || (r < 0 && errno == EINTR)) {
                ++k;
                continue;
            }
            Job& job = plan.jobs[running[k].job];
            job.seconds = secondsSince(running[k].start);
            job.peakMemoryMB = double(ru.ru_maxrss) / 1024.0;
            const std::string dir = jobDir(o.outDir, job);
            if (r > 0 && WIFEXITED(status)) {
                job.exitCode = WEXITSTATUS(status);
            } else {
                job.exitCode = r > 0 && WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
            }
            std::string why;
            if (job.exitCode == EXIT_OK && outputsVerified(dir, &why)) {
                job.state = "done";
                job.error.clear();
                if (job.warmStarted) job.warmStarted = startedWarm(dir);
            } else if (job.exitCode == EXIT_INTERRUPTED || stopping) {
                job.state = "interrupted";
                job.error = "interrupted";
            } else {
                job.state = "failed";
                job.error = job.exitCode == 127 ? "could not run " + exe
                            : job.exitCode == EXIT_OK
                                ? "outputs incomplete: " + why
                                : lastErrorLine((fs::path(dir) / "log.txt").string());
                if (job.error.empty()) job.error = "exit code " + std::to_string(job.exitCode);
            }
            ++finished;
            finishedSeconds += job.seconds;
            running.erase(running.begin() + std::ptrdiff_t(k));
            reaped = true;
            const int done = countState(plan, "done"), failed = countState(plan, "failed");
            const std::size_t remaining = todo.size() - next + running.size();
            const double left =
                double(remaining) * (finishedSeconds / finished) / double(std::max(1, concurrency));
            say("batch: " + job.name + " " + job.state +
                (job.state == "failed" ? " (" + job.error + ")" : "") + " in " +
                duration(job.seconds) + "; " + std::to_string(done) + "/" +
                std::to_string(plan.jobs.size()) + " done, " + std::to_string(failed) +
                " failed, " + std::to_string(running.size()) + " running" +
                (remaining > 0 && !stopping ? ", ~" + duration(left) + " left" : std::string()));
        }
        if (reaped) writePlan(o.outDir, plan);
        if (!reaped) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    // Jobs never started because of an interruption stay pending.
    writePlan(o.outDir, plan);
    const int done = countState(plan, "done"), failed = countState(plan, "failed");
    out << PROGRAM << ": batch " << (stopping ? "interrupted" : "finished") << ": " << done << "/"
        << plan.jobs.size() << " done, " << failed << " failed, " << duration(secondsSince(start))
        << "; " << (fs::path(o.outDir) / "plan.json").string() << "\n";
    for (const Job& j : plan.jobs)
        if (j.state == "failed")
            out << PROGRAM << ": failed: " << j.name << ": " << j.error << "\n";
    if (stopping) throw Interrupted{};
    return failed > 0 ? EXIT_JOBS_FAILED : EXIT_OK;
}

/// The array tasks of the plan's Slurm job still queued or running: job index -> state.
std::map<int, std::string>
activeSlurmTasks(const Plan& p)
{
    std::map<int, std::string> active;
    if (p.slurmJobId.empty()) return active;
    const auto [code, text] =
        capture("squeue -h -r -j " + shellQuote(p.slurmJobId) + " -o '%K %T'");
    if (code != 0) return active; // the job has left the queue (or squeue is not there)
    std::istringstream lines(text);
    std::string task, state;
    while (lines >> task >> state) {
        if (std::isdigit(static_cast<unsigned char>(task[0])))
            active[std::atoi(task.c_str())] = state;
    }
    return active;
}

/// Updates the states of the submitted jobs from squeue and their folders.
void
refreshSlurmStates(const std::string& outDir, Plan& p)
{
    const std::map<int, std::string> active = activeSlurmTasks(p);
    for (int k : p.slurmTasks) {
        if (k < 0 || k >= int(p.jobs.size())) continue;
        Job& j = p.jobs[std::size_t(k)];
        const auto it = active.find(k);
        if (it != active.end()) {
            j.state = it->second == "RUNNING" ? "running" : "pending";
            continue;
        }
        if (j.state == "done" || j.state == "failed") continue;
        const std::string dir = jobDir(outDir, j);
        std::string why;
        if (outputsVerified(dir, &why)) {
            j.state = "done";
            j.error.clear();
            // A task's time and memory, as its match reported them (no accounting needed).
            std::ifstream f(fs::path(dir) / "report.json");
            try {
                const Json report = Json::parse(f);
                const Json& r = report.at("result");
                j.seconds =
                    r.at("seconds").value("match", 0.0) + r.at("seconds").value("write", 0.0);
                j.peakMemoryMB = r.value("peakMemoryMB", 0.0);
                j.warmStarted = startedWarm(report);
            } catch (const Json::exception&) {
            }
        } else {
            j.state = "failed";
            j.error = lastErrorLine((fs::path(dir) / "log.txt").string());
            if (j.error.empty()) j.error = "no result (" + why + "); see the task's log in slurm/";
        }
    }
}

int
statusCommand(const std::string& outDir, std::ostream& out)
{
    Plan p = readPlan(outDir);
    if (p.executor == "slurm") {
        refreshSlurmStates(outDir, p);
        writePlan(outDir, p);
        out << "slurm job " << p.slurmJobId << "\n";
    }
    out << "plan " << p.kind << ", " << p.jobs.size() << " jobs: " << countState(p, "done")
        << " done, " << countState(p, "failed") << " failed, " << countState(p, "pending")
        << " pending, " << countState(p, "running") << " running, " << countState(p, "interrupted")
        << " interrupted\n";
    for (const Job& j : p.jobs) {
        out << j.name << "  " << j.state;
        if (j.seconds > 0) out << "  " << duration(j.seconds);
        if (j.warmStarted) out << "  (warm start)";
        if (!j.error.empty()) out << "  " << j.error;
        out << "\n";
    }
    return EXIT_OK;
}

std::string
frameName(const std::string& stem, int frame, const char* extension)
{
    char digits[32];
    std::snprintf(digits, sizeof(digits), "%04d", frame);
    return stem + "." + digits + extension;
}

/// For a sequence whose jobs are all done: the first frame's surface carried to every frame
/// (OUTDIR/sequence/deformed.####.obj, the first frame's elements with the vertices moved by
/// phi_{k-1} o ... o phi_0) and the composed maps from the first frame to every later one
/// (OUTDIR/sequence/composed.####.vdb: at every node x of the first job's grid, the
/// displacement phi_{k-1}(...phi_0(x)) - x, each map evaluated exactly).
Json
collectSequence(const std::string& outDir, const Plan& p, std::ostream& err, bool quiet)
{
    for (const Job& j : p.jobs)
        if (j.state != "done")
            OPENVDB_THROW(openvdb::ValueError, "batch collect: job " << j.name << " is " << j.state
                                                                     << "; the sequence outputs "
                                                                        "need every frame");
    const fs::path dir = fs::path(outDir) / "sequence";
    createOutputDirectory(dir.string());
    const Shape first = readInputShape(p.inputs[0], "");
    std::vector<openvdb::Vec3d> points;
    if (first.dim == 3) {
        for (const Vec<3>& v : first.surface.points)
            points.emplace_back(v[0], v[1], v[2]);
    } else {
        for (const Vec<2>& v : first.curve.points)
            points.emplace_back(v[0], v[1], 0.0);
    }
    auto writeMesh = [&](int frame) {
        const std::string path = (dir / frameName("deformed", frame, ".obj")).string();
        writeFileAtomically(path, [&](std::ostream& os) {
            if (first.dim == 3) {
                Surface<3> s = first.surface;
                for (std::size_t i = 0; i < points.size(); ++i)
                    s.points[i] = Vec<3>(points[i][0], points[i][1], points[i][2]);
                writeObj(os, s);
            } else {
                Surface<2> s = first.curve;
                for (std::size_t i = 0; i < points.size(); ++i)
                    s.points[i] = Vec<2>(points[i][0], points[i][1]);
                writeObj(os, s);
            }
        });
    };
    writeMesh(p.firstFrame);
    // The nodes of the first job's grid and their images so far.
    const DeformationField phi0 =
        DeformationField::read((fs::path(jobDir(outDir, p.jobs[0])) / "deformation.vdb").string());
    openvdb::Vec3SGrid::Ptr composed = phi0.grid().deepCopy();
    std::vector<openvdb::Coord> nodes;
    std::vector<openvdb::Vec3d> image;
    for (auto it = composed->cbeginValueOn(); it; ++it) {
        nodes.push_back(it.getCoord());
        image.push_back(composed->indexToWorld(it.getCoord()));
    }
    for (std::size_t k = 0; k < p.jobs.size(); ++k) {
        checkInterrupted();
        const int frame = p.firstFrame + int(k) + 1;
        if (!quiet) err << PROGRAM << ": sequence: frame " << frame << std::endl;
        const DeformationField phi =
            k == 0 ? phi0
                   : DeformationField::read(
                         (fs::path(jobDir(outDir, p.jobs[k])) / "deformation.vdb").string());
        phi.mapPoints(points, false);
        phi.mapPoints(image, false);
        writeMesh(frame);
        auto acc = composed->getAccessor();
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const openvdb::Vec3d d = image[i] - composed->indexToWorld(nodes[i]);
            acc.setValueOnly(nodes[i], openvdb::Vec3s(float(d[0]), float(d[1]), float(d[2])));
        }
        composed->removeMeta("vdbmatch_composed_frames");
        composed->insertMeta(
            "vdbmatch_composed_frames",
            openvdb::StringMetadata(std::to_string(p.firstFrame) + ".." + std::to_string(frame)));
        writeGridsAtomically((dir / frameName("composed", frame, ".vdb")).string(), {composed},
                             openvdb::MetaMap());
    }
    const int last = p.firstFrame + int(p.jobs.size());
    return Json{{"frames", {p.firstFrame, last}},
                {"meshes", "sequence/deformed.####.obj"},
                {"composedMaps", "sequence/composed.####.vdb"}};
}

/// `batch collect`: distances.csv (sqrt of the final energy of each match; the mean of both
/// directions where both ran), distances.png and mds.png for all pairs and summary.json (per job:
/// energy and terms, residual and target residual, min det, time, memory, |psi o phi - Id| where
/// both directions ran).
int
collectCommand(const std::string& outDir, std::ostream& out, std::ostream& err, bool quiet)
{
    Plan p = readPlan(outDir);
    if (p.executor == "slurm") {
        refreshSlurmStates(outDir, p);
        writePlan(outDir, p);
    }
    std::map<std::string, Json> reports;
    for (const Job& j : p.jobs) {
        if (j.state != "done") continue;
        std::ifstream f(fs::path(jobDir(outDir, j)) / "report.json");
        try {
            reports[j.name] = Json::parse(f);
        } catch (const Json::exception&) {
            OPENVDB_THROW(openvdb::ValueError, "job " << j.name << ": unreadable report.json");
        }
    }
    auto energyOf = [&](const std::string& a, const std::string& b) -> std::optional<double> {
        auto it = reports.find(stemOf(a) + "--" + stemOf(b));
        if (it == reports.end()) return std::nullopt;
        // E is quadratic in the deformation (a squared length, like a path energy): its square
        // root is the distance.
        return std::sqrt(std::max(0.0, it->second.at("result").at("energy").get<double>()));
    };
    // distances.csv: rows the sources, columns the targets (all pairs: a symmetric matrix).
    std::vector<std::string> rows, cols;
    if (p.kind == "template") {
        rows = {p.inputs[0]};
        cols.assign(p.inputs.begin() + 1, p.inputs.end());
    } else {
        rows = cols = p.inputs;
    }
    std::ostringstream csv;
    csv << "shape";
    for (const std::string& c : cols)
        csv << "," << stemOf(c);
    csv << "\n";
    for (const std::string& r : rows) {
        csv << stemOf(r);
        for (const std::string& c : cols) {
            csv << ",";
            if (r == c) {
                csv << 0;
                continue;
            }
            const auto ab = energyOf(r, c);
            const auto ba = p.kind == "template" ? std::nullopt : energyOf(c, r);
            if (ab && ba) {
                csv << formatNumber(0.5 * (*ab + *ba));
            } else if (ab || ba) {
                csv << formatNumber(ab ? *ab : *ba);
            }
        }
        csv << "\n";
    }
    writeFileAtomically((fs::path(outDir) / "distances.csv").string(),
                        [&](std::ostream& os) { os << csv.str(); });

    Json jobs = Json::array();
    for (const Job& j : p.jobs) {
        Json e{{"name", j.name},   {"source", j.source},   {"target", j.target},
               {"state", j.state}, {"seconds", j.seconds}, {"peakMemoryMB", j.peakMemoryMB}};
        if (!j.error.empty()) e["error"] = j.error;
        if (j.warmFrom >= 0) e["warmStarted"] = j.warmStarted;
        auto it = reports.find(j.name);
        if (it != reports.end()) {
            const Json& res = it->second.at("result");
            e["energy"] = res.at("energy");
            if (res.contains("terms")) e["terms"] = res.at("terms");
            e["residual"] = res.at("residual");
            // Reports written before the target residual (2026-11-28) have none.
            if (res.contains("targetResidual")) e["targetResidual"] = res.at("targetResidual");
            e["minJacobian"] = res.at("minJacobian");
            // The inputs' small pieces (scan debris), from reports written since 2026-11-28.
            const Json& rep = it->second;
            if (rep.contains("source") && rep.at("source").contains("smallPieces")) {
                e["smallPieces"] = Json{{"source", rep.at("source").at("smallPieces")},
                                        {"target", rep.at("target").at("smallPieces")}};
            }
            // |psi o phi - Id| where the reverse job ran too (the consistency command).
            const std::string reverse = stemOf(j.target) + "--" + stemOf(j.source);
            if (reports.count(reverse)) {
                const std::string phi = (fs::path(jobDir(outDir, j)) / "deformation.vdb").string();
                const std::string psi =
                    (fs::path(jobDir(outDir, reverse)) / "deformation.vdb").string();
                std::vector<std::string> args = {PROGRAM,    "consistency", phi,
                                                 psi,        "--source",    j.source,
                                                 "--target", j.target,      "--json"};
                std::vector<const char*> argv;
                for (const std::string& a : args)
                    argv.push_back(a.c_str());
                std::ostringstream cout_, cerr_;
                if (!quiet) err << PROGRAM << ": consistency of " << j.name << std::endl;
                if (run(int(argv.size()), argv.data(), cout_, cerr_) == EXIT_OK) {
                    const Json c = Json::parse(cout_.str());
                    e["psiPhiMinusId"] = c.at("psi_phi");
                } else {
                    e["psiPhiMinusId"] = cerr_.str();
                }
            }
        }
        jobs.push_back(e);
    }
    // All pairs: the matrix as a heat map in the order of a hierarchical clustering, and the
    // shapes placed in the plane by MDS.
    Json pictures = Json::object();
    if (p.kind == "all-pairs") {
        eval::DistanceMatrix m;
        m.n = int(p.inputs.size());
        m.d.assign(std::size_t(m.n) * std::size_t(m.n), std::numeric_limits<double>::quiet_NaN());
        std::vector<std::string> names;
        for (int i = 0; i < m.n; ++i) {
            names.push_back(stemOf(p.inputs[std::size_t(i)]));
            for (int j = 0; j < m.n; ++j) {
                if (i == j) {
                    m.d[std::size_t(i * m.n + j)] = 0;
                    continue;
                }
                const auto ab = energyOf(p.inputs[std::size_t(i)], p.inputs[std::size_t(j)]);
                const auto ba = energyOf(p.inputs[std::size_t(j)], p.inputs[std::size_t(i)]);
                if (ab || ba)
                    m.d[std::size_t(i * m.n + j)] = ab && ba ? 0.5 * (*ab + *ba) : ab ? *ab : *ba;
            }
        }
        const std::vector<int> order = eval::clusterOrder(m);
        const Image8 heat = render::distanceHeatMap(m, names, order, "distance sqrt(E), clustered");
        writePng((fs::path(outDir) / "distances.png").string(), heat.width, heat.height, heat.rgb);
        Json ordered = Json::array();
        for (int k : order)
            ordered.push_back(names[std::size_t(k)]);
        pictures["distances.png"] = "heat map of distances.csv, rows and columns in clusterOrder";
        pictures["clusterOrder"] = ordered;
        if (m.n >= 3) {
            const Image8 mds =
                render::labelledScatter(eval::classicalMds(m), names, "classical MDS of sqrt(E)");
            writePng((fs::path(outDir) / "mds.png").string(), mds.width, mds.height, mds.rgb);
            pictures["mds.png"] = "the shapes placed in the plane by classical MDS";
        }
    }
    Json sequence;
    if (p.kind == "sequence" && countState(p, "done") == int(p.jobs.size()))
        sequence = collectSequence(outDir, p, err, quiet);
    Json summary{{"plan", p.kind},
                 {"jobs", int(p.jobs.size())},
                 {"done", countState(p, "done")},
                 {"failed", countState(p, "failed")},
                 {"distance", "final energy E of the match (eq:Esym for the symmetric "
                              "energy); the mean of both directions where both ran"},
                 {"results", jobs}};
    if (!sequence.is_null()) summary["sequence"] = sequence;
    if (!pictures.empty()) summary["pictures"] = pictures;
    const std::string text = dumpJson(summary);
    writeFileAtomically((fs::path(outDir) / "summary.json").string(),
                        [&](std::ostream& os) { os << text; });
    out << PROGRAM << ": wrote " << (fs::path(outDir) / "distances.csv").string() << ", "
        << (fs::path(outDir) / "summary.json").string() << " (" << reports.size() << " of "
        << p.jobs.size() << " jobs done)\n";
    return EXIT_OK;
}

/// `--executor slurm`: the jobs not yet done as one job array (array index = job index), the
/// script OUTDIR/slurm/batch.sbatch running line k + 1 of OUTDIR/jobs.txt for task k.
int
submitSlurm(const BatchCliOptions& o, Plan& plan, std::ostream& out, std::ostream& err)
{
    auto say = [&](const std::string& text) {
        if (!o.quiet) err << PROGRAM << ": " << text << std::endl;
    };
    const std::map<int, std::string> active = activeSlurmTasks(plan);
    if (!active.empty()) {
        throw UsageError("slurm job " + plan.slurmJobId + " of this batch still has " +
                         std::to_string(active.size()) +
                         " task(s) queued or running; wait for it (batch status) or scancel it");
    }
    refreshSlurmStates(o.outDir, plan);
    std::vector<int> todo;
    for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
        Job& j = plan.jobs[i];
        if (j.state == "done" && outputsVerified(jobDir(o.outDir, j))) continue;
        j.state = "pending";
        j.error.clear();
        todo.push_back(int(i));
    }
    if (todo.empty()) {
        writePlan(o.outDir, plan);
        out << PROGRAM << ": batch: all " << plan.jobs.size() << " jobs done; nothing to submit\n";
        return EXIT_OK;
    }
    const std::string exe = selfExecutable();
    // One thread per task (tasks in parallel do more work per core); a warm-start chain runs
    // one task at a time, in index order (%1), each with two threads.
    const int threads = o.threadsPerJob > 0 ? o.threadsPerJob : plan.warmStart ? 2 : 1;
    writeJobList(o.outDir, plan, exe, threads);
    const fs::path slurmDir = fs::path(absolutePath(o.outDir)) / "slurm";
    createOutputDirectory(slurmDir.string());
    std::string array;
    for (std::size_t k = 0; k < todo.size(); ++k)
        array += (k ? "," : "") + std::to_string(todo[k]);
    if (plan.warmStart) {
        if (o.arrayThrottle > 1)
            say("batch: --warm-start runs the tasks one at a time; --array-throttle ignored");
        array += "%1";
    } else if (o.arrayThrottle > 0) {
        array += "%" + std::to_string(o.arrayThrottle);
    }
    const int memory = o.memoryPerTaskMB > 0 ? o.memoryPerTaskMB
                                             : defaultMemoryMB(finestLevel(plan.matchArguments));
    const std::string jobs = (fs::path(absolutePath(o.outDir)) / "jobs.txt").string();
    std::ostringstream script;
    script << "#!/bin/bash\n"
           << "# vdb_match batch: " << plan.jobs.size() << " jobs of plan " << plan.kind
           << "; array task k runs line k+1 of jobs.txt (docs/batch.md).\n"
           << "#SBATCH --job-name=vdbmatch\n"
           << "#SBATCH --array=" << array << "\n"
           << "#SBATCH --cpus-per-task=" << threads << "\n"
           << "#SBATCH --mem=" << memory << "M\n"
           << "#SBATCH --output=" << (slurmDir / "task_%A_%a.log").string() << "\n"
           << "set -eu\n"
           << "line=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" " << shellQuote(jobs) << ")\n"
           << "exec bash -c \"$line\"\n";
    const std::string scriptPath = (slurmDir / "batch.sbatch").string();
    writeFileAtomically(scriptPath, [&](std::ostream& os) { os << script.str(); });
    const auto [code, text] = capture("sbatch --parsable " + shellQuote(scriptPath));
    if (code != 0) {
        writePlan(o.outDir, plan);
        OPENVDB_THROW(openvdb::IoError,
                      "sbatch " << (code == 127 ? "is not installed (no Slurm here?)"
                                                : "refused the job array: " + firstLine(text))
                                << "; the script is " << scriptPath);
    }
    plan.executor = "slurm";
    plan.slurmJobId = firstLine(text).substr(0, firstLine(text).find(';'));
    plan.slurmTasks = todo;
    for (int k : todo)
        plan.jobs[std::size_t(k)].state = "pending";
    writePlan(o.outDir, plan);
    say("batch: submitted slurm job " + plan.slurmJobId + " (" + std::to_string(todo.size()) +
        " array tasks, " + std::to_string(threads) + " CPU and " + std::to_string(memory) +
        " MB each)");
    if (!o.wait) {
        out << PROGRAM << ": batch submitted as slurm job " << plan.slurmJobId
            << "; follow it with " << PROGRAM << " batch status " << o.outDir << "\n";
        return EXIT_OK;
    }
    // --wait: follow the array until no task is queued or running.
    const Clock::time_point start = Clock::now();
    std::string last;
    while (true) {
        if (wasSignalled()) {
            capture("scancel " + shellQuote(plan.slurmJobId));
            refreshSlurmStates(o.outDir, plan);
            writePlan(o.outDir, plan);
            throw Interrupted{};
        }
        refreshSlurmStates(o.outDir, plan);
        const int running = countState(plan, "running"), pending = countState(plan, "pending");
        const std::string now =
            std::to_string(countState(plan, "done")) + "/" + std::to_string(plan.jobs.size()) +
            " done, " + std::to_string(countState(plan, "failed")) + " failed, " +
            std::to_string(running) + " running, " + std::to_string(pending) + " queued";
        if (now != last) {
            writePlan(o.outDir, plan);
            say("batch: " + now);
            last = now;
        }
        if (running == 0 && pending == 0) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
    const int failed = countState(plan, "failed");
    out << PROGRAM << ": batch finished: " << countState(plan, "done") << "/" << plan.jobs.size()
        << " done, " << failed << " failed, " << duration(secondsSince(start)) << "; "
        << (fs::path(o.outDir) / "plan.json").string() << "\n";
    for (const Job& j : plan.jobs)
        if (j.state == "failed")
            out << PROGRAM << ": failed: " << j.name << ": " << j.error << "\n";
    return failed > 0 ? EXIT_JOBS_FAILED : EXIT_OK;
}

} // namespace

std::string
batchOptionHelp()
{
    return optionHelp(batchOptionTable());
}

std::vector<OptionDescription>
batchOptionDescriptions()
{
    return describeOptions(batchOptionTable());
}

int
runBatchCommand(int argc, const char* const* argv, int first, std::ostream& out, std::ostream& err)
{
    // Options of each match follow `--`.
    int sep = argc;
    for (int i = first; i < argc; ++i)
        if (std::string(argv[i]) == "--") {
            sep = i;
            break;
        }
    std::vector<std::string> matchArgs(argv + std::min(sep + 1, argc), argv + argc);
    for (const std::string& a : matchArgs) {
        if (a == "-o" || a == "--output" || a.rfind("--output=", 0) == 0 || a == "--source" ||
            a == "--target" || a == "--threads" || a == "--quiet" || a == "--init" ||
            a == "--warm-start") {
            throw UsageError("batch: '" + a + "' after -- is set by batch for each job");
        }
    }
    BatchCliOptions o;
    std::vector<std::string> positional = parseOptions(batchOptionTable(), sep, argv, first, o);
    openvdb::initialize();
    if (!positional.empty() && (positional[0] == "status" || positional[0] == "collect")) {
        const std::string dir = positional.size() > 1 ? positional[1] : o.outDir;
        if (dir.empty()) throw UsageError("batch " + positional[0] + " OUTDIR");
        return positional[0] == "status" ? statusCommand(dir, out)
                                         : collectCommand(dir, out, err, o.quiet);
    }
    if (o.outDir.empty()) throw UsageError("batch: missing -o OUTDIR");
    if (o.jobs < 0 || o.threadsPerJob < 0)
        throw UsageError("--jobs and --threads-per-job must be >= 0");
    SignalScope signals;
    Plan plan = makePlan(o, positional, matchArgs);
    createOutputDirectory(o.outDir);
    const OutputLock lock(o.outDir);
    // The same command again resumes; another plan in the same directory is refused.
    std::error_code ec;
    if (fs::exists(fs::path(o.outDir) / "plan.json", ec)) {
        Plan old = readPlan(o.outDir);
        if (old.kind != plan.kind || old.inputs != plan.inputs || old.warmStart != plan.warmStart ||
            old.matchArguments != plan.matchArguments || old.jobs.size() != plan.jobs.size()) {
            throw UsageError("'" + o.outDir +
                             "' holds another batch (other plan, inputs or match options); "
                             "use another -o, or remove it");
        }
        plan.executor = old.executor;
        plan.slurmJobId = old.slurmJobId;
        plan.slurmTasks = old.slurmTasks;
        for (std::size_t i = 0; i < plan.jobs.size(); ++i) {
            plan.jobs[i].state = old.jobs[i].state;
            plan.jobs[i].seconds = old.jobs[i].seconds;
            plan.jobs[i].peakMemoryMB = old.jobs[i].peakMemoryMB;
            plan.jobs[i].exitCode = old.jobs[i].exitCode;
            plan.jobs[i].warmStarted = old.jobs[i].warmStarted;
        }
    }
    if (o.executor == "slurm") return submitSlurm(o, plan, out, err);
    if (plan.executor == "slurm" && !activeSlurmTasks(plan).empty()) {
        throw UsageError("slurm job " + plan.slurmJobId +
                         " of this batch is still queued or running; wait for it (batch status)");
    }
    plan.executor = "local";
    writeJobList(o.outDir, plan, selfExecutable(), 1);
    return runPlan(o, plan, out, err);
}

} // namespace cli
} // namespace vdbmatch
