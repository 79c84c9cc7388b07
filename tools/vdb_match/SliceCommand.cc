/// @file SliceCommand.cc
/// @brief `vdb_match slice PHI.vdb --source M1 --target M2 -o OUT.exr`: a plane of Omega sampled
///        into a float OpenEXR image (inverse_error, residual, det, displacement, d1, d2) and one
///        PNG preview per channel, OUT.<channel>.png (docs/cli.md).
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/eval/SliceImage.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/io/ShapeIO.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cctype>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

/// Extension of the output file.
constexpr const char* EXR_EXTENSION = ".exr";

struct SliceCliOptions
{
    std::string phi, psi, source, target, sourceGrid, targetGrid, output;
    std::optional<int> axis;
    std::optional<double> position, unitPosition;
    int resolution = 0;
    int distanceLevel = 0;
    int threads = 0;
    bool quiet = false;
    std::string commandLine;
};

std::vector<Option<SliceCliOptions>>
sliceOptionTable()
{
    using O = SliceCliOptions;
    // clang-format off
    return {
        {"--output,-o", "OUT.exr", "Input and output",
         "the EXR file to write (required); the previews go to OUT.<channel>.png",
         [](O& o, const std::string& v) { o.output = v; }},
        {"--source", "M1", "Input and output", "the source shape of PHI (required)",
         [](O& o, const std::string& v) { o.source = v; }},
        {"--target", "M2", "Input and output", "the target shape of PHI (required)",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--inverse", "PSI.vdb", "Input and output",
         "the deformation of M2 -> M1: adds the channel inverse_error = |psi(phi(x)) - x|",
         [](O& o, const std::string& v) { o.psi = v; }},
        {"--source-grid", "NAME", "Input and output", "grid to read from a .vdb M1",
         [](O& o, const std::string& v) { o.sourceGrid = v; }},
        {"--target-grid", "NAME", "Input and output", "grid to read from a .vdb M2",
         [](O& o, const std::string& v) { o.targetGrid = v; }},
        {"--axis", "x|y|z", "Plane",
         "normal of the plane (default z; a 2D deformation is sliced in its own plane, z)",
         [](O& o, const std::string& v) {
             if (v == "x") o.axis = 0;
             else if (v == "y") o.axis = 1;
             else if (v == "z") o.axis = 2;
             else throw UsageError("--axis expects x, y or z, got '" + v + "'");
         }},
        {"--position", "X", "Plane",
         "world coordinate of the plane along the axis (3D; default: the centre of M1's bounding "
         "box)",
         [](O& o, const std::string& v) { o.position = parseDouble("--position", v); }},
        {"--unit-position", "T", "Plane",
         "the position as a fraction of the domain along the axis, in [0, 1] (3D; not with "
         "--position)",
         [](O& o, const std::string& v) { o.unitPosition = parseDouble("--unit-position", v); }},
        {"--resolution", "N", "Plane",
         "pixels along the longer side of the plane (default: one pixel per voxel of PHI)",
         [](O& o, const std::string& v) { o.resolution = parseInt("--resolution", v); }},
        {"--distance-level", "L", "Plane",
         "level 2^-L of the distance grids of d1 and d2 (default: one finer than PHI, 7..8 in "
         "3D, 9..11 in 2D)",
         [](O& o, const std::string& v) { o.distanceLevel = parseInt("--distance-level", v); }},
        {"--quiet", nullptr, "Execution", "do not list the files written",
         [](O& o, const std::string&) { o.quiet = true; }},
        {"--threads", "N", "Execution", "number of threads, 0 = all cores (default 0)",
         [](O& o, const std::string& v) { o.threads = parseThreads(v); }},
    };
    // clang-format on
}

bool
endsWithExr(const std::string& path)
{
    const std::string ext = EXR_EXTENSION;
    if (path.size() <= ext.size()) return false;
    std::string tail = path.substr(path.size() - ext.size());
    std::transform(tail.begin(), tail.end(), tail.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return tail == ext;
}

SliceCliOptions
parseSliceOptions(int argc, const char* const* argv, int first)
{
    SliceCliOptions o;
    o.commandLine = commandLine(argc, argv);
    const std::vector<std::string> positional =
        parseOptions(sliceOptionTable(), argc, argv, first, o);
    if (positional.size() != 1) {
        throw UsageError("slice expects one deformation PHI.vdb, got " +
                         std::to_string(positional.size()) + " file argument(s)");
    }
    o.phi = positional[0];
    if (o.source.empty() || o.target.empty()) {
        throw UsageError("slice needs the shapes: --source M1 --target M2");
    }
    if (o.output.empty()) throw UsageError("missing the output file: -o OUT.exr");
    if (!endsWithExr(o.output)) {
        throw UsageError("the output file must end in .exr, got '" + o.output + "'");
    }
    if (o.position && o.unitPosition) {
        throw UsageError("--position and --unit-position cannot be combined");
    }
    if (o.resolution < 0) throw UsageError("--resolution must be >= 2");
    if (o.threads < 0) throw UsageError("--threads must be >= 0");
    if (o.distanceLevel < 0) throw UsageError("--distance-level must be >= 1");
    return o;
}

Shape
readShapeInput(const std::string& path, const std::string& gridName, const char* option)
{
    if (!gridName.empty() && isShapeFile(path) && !isLevelSetFile(path)) {
        throw UsageError(std::string(option) + " applies to .vdb shapes, not to '" + path + "'");
    }
    return readShape(path, gridName);
}

} // namespace

std::string
slicePreviewPath(const std::string& exrPath, const std::string& channel)
{
    const std::string stem =
        endsWithExr(exrPath) ? exrPath.substr(0, exrPath.size() - std::string(EXR_EXTENSION).size())
                             : exrPath;
    return stem + "." + channel + ".png";
}

int
runSliceCommand(int argc, const char* const* argv, int first, std::ostream& out, std::ostream&)
{
    const SliceCliOptions o = parseSliceOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    const DeformationField phi = DeformationField::read(o.phi);
    std::optional<DeformationField> psi;
    if (!o.psi.empty()) psi.emplace(DeformationField::read(o.psi));
    const Shape m1 = readShapeInput(o.source, o.sourceGrid, "--source-grid");
    const Shape m2 = readShapeInput(o.target, o.targetGrid, "--target-grid");
    checkInterrupted();
    if (m1.dim != m2.dim) {
        OPENVDB_THROW(openvdb::ValueError, "M1 is " + std::to_string(m1.dim) + "D and M2 " +
                                               std::to_string(m2.dim) + "D");
    }
    eval::SliceOptions opts;
    opts.axis = o.axis;
    opts.position = o.position;
    opts.unitPosition = o.unitPosition;
    opts.resolution = o.resolution;
    opts.distanceLevel = o.distanceLevel;
    SignalInterrupter interrupter;
    const DeformationField* psiPtr = psi ? &*psi : nullptr;
    eval::SliceImage slice;
    try {
        slice = m1.dim == 2
                    ? eval::sampleSlice<2>(phi, psiPtr, m1.curve, m2.curve, opts, &interrupter)
                    : eval::sampleSlice<3>(phi, psiPtr, m1.surface, m2.surface, opts, &interrupter);
    } catch (const openvdb::RuntimeError&) {
        checkInterrupted();
        throw;
    }
    checkInterrupted();

    const char* const axisNames[] = {"x", "y", "z"};
    ImageAttributes attributes = {
        {"vdbmatch:axis", axisNames[slice.axis]},
        {"vdbmatch:position", formatNumber(slice.position)},
        {"vdbmatch:unit_position", formatNumber(slice.unitPosition)},
        {"vdbmatch:units", "world"},
        {"vdbmatch:pixel_size", formatNumber(slice.pixelSize)},
        {"vdbmatch:origin", formatNumber(slice.origin[0]) + " " + formatNumber(slice.origin[1]) +
                                " " + formatNumber(slice.origin[2])},
        {"vdbmatch:column_axis", axisNames[slice.columnAxis]},
        {"vdbmatch:row_axis", axisNames[slice.rowAxis]},
        {"vdbmatch:domain_size", formatNumber(slice.domainSize)},
        {"vdbmatch:phi", o.phi},
        {"vdbmatch:source", o.source},
        {"vdbmatch:target", o.target},
        {"vdbmatch:command", o.commandLine},
        {"vdbmatch:version", VDBMATCH_VERSION},
    };
    if (psi) attributes.push_back({"vdbmatch:psi", o.psi});
    writeExr(o.output, slice.image, attributes);
    if (!o.quiet) out << o.output << "\n";
    for (const std::string& channel : slice.image.names) {
        checkInterrupted();
        const Image8 preview = eval::renderSlicePreview(slice, channel);
        const std::string path = slicePreviewPath(o.output, channel);
        writePng(path, preview.width, preview.height, preview.rgb);
        if (!o.quiet) out << path << "\n";
    }
    out.flush();
    return EXIT_OK;
}

std::string
sliceOptionHelp()
{
    return optionHelp(sliceOptionTable());
}

std::vector<OptionDescription>
sliceOptionDescriptions()
{
    return describeOptions(sliceOptionTable());
}

} // namespace cli
} // namespace vdbmatch
