/// @file module.cc
/// @brief vdbmatch._vdbmatch, the compiled half of the Python module: the vdb_match commands run
///        in-process (cli::run with RunHooks: progress to a Python callable, the GIL released,
///        Ctrl-C and a cancelling callback stop the command), their option tables as data, and
///        a deformation read once and applied to numpy arrays of points (exact phi and phi^-1).
///
/// The pure-Python half (python/vdbmatch/__init__.py) turns shapes and keywords into a command
/// line and results into objects; see docs/python.md.
#include "Cli.h"

#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>

#include <atomic>
#include <limits>
#include <mutex>
#include <optional>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <sstream>
#include <string>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace py = pybind11;
using namespace vdbmatch;

namespace {

/// The allocator settings of the vdb_match executable (tools/vdb_match/main.cc): freed work
/// arrays are kept for the next iteration instead of being unmapped and faulted in again.
/// Process-wide; applied once, before the first command (docs/python.md).
void
tuneAllocatorOnce()
{
#if defined(__GLIBC__)
    static const bool done = [] {
        mallopt(M_MMAP_THRESHOLD, 32 << 20);
        mallopt(M_TRIM_THRESHOLD, std::numeric_limits<int>::max());
        return true;
    }();
    (void)done;
#endif
}

const char*
kindName(cli::ProgressEvent::Kind k)
{
    switch (k) {
    case cli::ProgressEvent::Kind::LevelStart:
        return "level_start";
    case cli::ProgressEvent::Kind::Iteration:
        return "iteration";
    case cli::ProgressEvent::Kind::LevelEnd:
        return "level_end";
    case cli::ProgressEvent::Kind::Message:
        break;
    }
    return "message";
}

/// Runs `vdb_match ARGS...`; returns (exit code, stdout, stderr). @a progress (or None) is called
/// with a dict per progress event; if it raises, the command stops and the exception propagates.
py::tuple
runCommand(const std::vector<std::string>& args, py::object progress, bool handleSignals)
{
    tuneAllocatorOnce();
    std::vector<std::string> argvStrings;
    argvStrings.reserve(args.size() + 1);
    argvStrings.emplace_back("vdb_match");
    argvStrings.insert(argvStrings.end(), args.begin(), args.end());
    std::vector<const char*> argv;
    for (const std::string& a : argvStrings)
        argv.push_back(a.c_str());

    std::atomic<bool> cancel{false};
    std::optional<py::error_already_set> callbackError;
    cli::RunHooks hooks;
    hooks.cancel = &cancel;
    hooks.handleSignals = handleSignals;
    if (!progress.is_none()) {
        hooks.progress = [&](const cli::ProgressEvent& e) {
            if (callbackError) return;
            py::gil_scoped_acquire gil;
            try {
                py::dict d;
                d["kind"] = kindName(e.kind);
                d["level"] = e.level;
                d["first_level"] = e.firstLevel;
                d["last_level"] = e.lastLevel;
                d["iteration"] = e.iteration;
                d["energy"] = e.energy;
                d["elapsed"] = e.elapsedSeconds;
                d["seconds_left"] = e.secondsLeft < 0 ? py::object(py::none())
                                                      : py::object(py::float_(e.secondsLeft));
                d["text"] = e.text;
                progress(d);
            } catch (py::error_already_set& ex) {
                callbackError.emplace(std::move(ex));
                cancel = true;
            }
        };
    }
    std::ostringstream out, err;
    int code = 0;
    {
        py::gil_scoped_release release;
        // The commands keep their interruption flag and hooks in process-wide state, and each
        // uses every core: calls from several Python threads run one after the other.
        static std::mutex runMutex;
        const std::lock_guard<std::mutex> lock(runMutex);
        code = cli::run(int(argv.size()), argv.data(), out, err, hooks);
    }
    if (callbackError) throw std::move(*callbackError);
    return py::make_tuple(code, out.str(), err.str());
}

py::list
optionTable(const std::string& command)
{
    py::list rows;
    for (const cli::OptionDescription& d : cli::commandOptions(command)) {
        py::dict row;
        row["name"] = d.name;
        row["metavar"] = d.metavar;
        row["values"] = d.values;
        row["group"] = d.group;
        row["help"] = d.help;
        rows.append(row);
    }
    return rows;
}

/// A deformation file read once: phi (or phi^-1) applied to arrays of points.
class PyDeformation
{
public:
    explicit PyDeformation(const std::string& path) : mField(readField(path)) {}

    int dimension() const { return mField.dimension(); }

    /// Maps an (n, d) array of world positions; returns the mapped (n, d) array and the number
    /// of points whose inverse walk failed.
    std::pair<py::array_t<double>, std::size_t>
    map(py::array_t<double, py::array::c_style | py::array::forcecast> points, bool inverse) const
    {
        const int d = mField.dimension();
        if (points.ndim() != 2 || points.shape(1) != d) {
            throw py::value_error("points: the deformation is " + std::to_string(d) +
                                  "D, expected an (n, " + std::to_string(d) +
                                  ") array, got shape " + shapeText(points));
        }
        const std::size_t n = std::size_t(points.shape(0));
        const int columns = d;
        // In 3D the result array is mapped in place (the (n, 3) doubles are n Vec3d); in 2D the
        // points go through a (n, 3) work array in the grid's plane.
        py::array_t<double> result({py::ssize_t(n), py::ssize_t(columns)});
        const double* in = points.data();
        double* outData = result.mutable_data();
        std::size_t failures = 0;
        {
            py::gil_scoped_release release;
            if (columns == 3) {
                std::copy(in, in + 3 * n, outData);
                failures = mField.mapPoints(reinterpret_cast<openvdb::Vec3d*>(outData), n, inverse);
            } else {
                std::vector<openvdb::Vec3d> work(n);
                for (std::size_t i = 0; i < n; ++i)
                    work[i] = openvdb::Vec3d(in[2 * i], in[2 * i + 1], 0.0);
                failures = mField.mapPoints(work.data(), n, inverse);
                for (std::size_t i = 0; i < n; ++i) {
                    outData[2 * i] = work[i][0];
                    outData[2 * i + 1] = work[i][1];
                }
            }
        }
        return {result, failures};
    }

private:
    static DeformationField readField(const std::string& path)
    {
        openvdb::initialize();
        return DeformationField::read(path);
    }

    static std::string shapeText(const py::array& a)
    {
        std::string s = "(";
        for (py::ssize_t i = 0; i < a.ndim(); ++i)
            s += (i ? ", " : "") + std::to_string(a.shape(i));
        return s + (a.ndim() == 1 ? ",)" : ")");
    }

    DeformationField mField;
};

} // namespace

PYBIND11_MODULE(_vdbmatch, m)
{
    m.doc() = "The compiled half of vdbmatch: the vdb_match commands in-process, their option "
              "tables, and deformations applied to numpy arrays. Use the vdbmatch package.";
    m.attr("__version__") = VDBMATCH_VERSION;
    m.attr("EXIT_OK") = int(cli::EXIT_OK);
    m.attr("EXIT_USAGE") = int(cli::EXIT_USAGE);
    m.attr("EXIT_IO") = int(cli::EXIT_IO);
    m.attr("EXIT_INVALID_INPUT") = int(cli::EXIT_INVALID_INPUT);
    m.attr("EXIT_NOT_CONVERGED") = int(cli::EXIT_NOT_CONVERGED);
    m.attr("EXIT_INTERRUPTED") = int(cli::EXIT_INTERRUPTED);
    m.def("run", &runCommand, py::arg("args"), py::arg("progress") = py::none(),
          py::arg("handle_signals") = true,
          "Runs `vdb_match ARGS...` in this process with the GIL released; returns (exit code, "
          "stdout, stderr). progress(dict) is called per progress event; an exception it raises "
          "stops the command and propagates. With handle_signals (main thread only), SIGINT "
          "stops the command with exit code EXIT_INTERRUPTED.");
    m.def("options", &optionTable, py::arg("command"),
          "The options of a command as dicts: name, metavar, values, group, help.");
    py::class_<PyDeformation>(m, "Deformation",
                              "A deformation.vdb read once (the displacement grid of phi).")
        .def(py::init<const std::string&>(), py::arg("path"))
        .def_property_readonly("dimension", &PyDeformation::dimension)
        .def("map", &PyDeformation::map, py::arg("points"), py::arg("inverse") = false,
             "Maps an (n, d) float array of world positions by phi (or the exact phi^-1); "
             "returns (mapped array, number of failed inverse walks).");
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const openvdb::IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const openvdb::Exception& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });
}
