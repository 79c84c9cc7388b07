/// @file CliSupport.cc
#include "CliSupport.h"

#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <sstream>

namespace vdbmatch {
namespace cli {

const char* const PROGRAM = "vdb_match";

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

namespace {

std::atomic<bool> sInterrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void
onSignal(int sig)
{
    sInterrupted.store(true);
    std::signal(sig, SIG_DFL); // a second signal terminates at once
}

} // namespace

SignalScope::SignalScope()
{
    sInterrupted.store(false);
    mInt = std::signal(SIGINT, onSignal);
    mTerm = std::signal(SIGTERM, onSignal);
}

SignalScope::~SignalScope()
{
    std::signal(SIGINT, mInt);
    std::signal(SIGTERM, mTerm);
}

bool
wasSignalled()
{
    return sInterrupted.load();
}

void
checkInterrupted()
{
    if (sInterrupted.load()) throw Interrupted{};
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
    return Json{{"cMatch", p.cMatch}, {"cMem", p.cMem},
                {"cBend", p.cBend},   {"cVol", p.cVol},
                {"q", p.q},           {"theta", p.theta},
                {"tau", p.tau},       {"sigmaFactor", p.sigmaFactor}};
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
