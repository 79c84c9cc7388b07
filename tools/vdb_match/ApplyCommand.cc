/// @file ApplyCommand.cc
/// @brief `vdb_match apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse]`: carry a mesh, a point
///        file or the grids of a .vdb file through a deformation (docs/apply.md).
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/eval/ShapeDistance.h>
#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/InverseGrid.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/io/MeshDocument.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/io/PointTable.h>
#include <vdbmatch/io/ShapeIO.h>
#include <vdbmatch/io/VdbFileCheck.h>
#include <vdbmatch/transport/GridTransport.h>
#include <vdbmatch/transport/MeshTransport.h>

#include <openvdb/openvdb.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

namespace fs = std::filesystem;

/// Options of `apply`.
struct ApplyCliOptions
{
    std::string deformation; ///< DEFORMATION.vdb (positional)
    std::string input;       ///< INPUT (positional)
    std::string output;      ///< -o, --output
    std::string target;      ///< --target: the shape the output should lie on (residual)
    std::string grid;        ///< --grid: the only grid of a .vdb input to carry
    bool inverse = false;
    bool attributes = false;
    int threads = 0;
    bool quiet = false;
};

std::vector<Option<ApplyCliOptions>>
applyOptionTable()
{
    using O = ApplyCliOptions;
    // clang-format off
    return {
        {"--output,-o", "OUTPUT", "Output",
         "the carried file, same format as INPUT (required). Written atomically: on "
         "any error no file is left",
         [](O& o, const std::string& v) { o.output = v; }},
        {"--inverse", nullptr, "Map",
         "carry by the exact inverse phi^-1 (target space -> source space) instead of phi",
         [](O& o, const std::string&) { o.inverse = true; }},
        {"--attributes", nullptr, "Output",
         "PLY meshes: add per-vertex properties det_jacobian, area_stretch and displacement (and "
         "residual with --target)",
         [](O& o, const std::string&) { o.attributes = true; }},
        {"--target", "SHAPE", "Output",
         "with --attributes: the shape the carried mesh should lie on (M2 for phi, M1 with "
         "--inverse); adds the residual |d(x')|, world units",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--grid", "NAME", "Input", ".vdb input: carry only this grid (default: every grid)",
         [](O& o, const std::string& v) { o.grid = v; }},
        {"--threads", "N", "Run", "worker threads (default: all cores)",
         [](O& o, const std::string& v) { o.threads = parseThreads(v); }},
        {"--quiet", nullptr, "Run", "no progress messages on stderr",
         [](O& o, const std::string&) { o.quiet = true; }},
    };
    // clang-format on
}

/// The lower-case extension of @a path, with the dot ("" if none).
std::string
extensionOf(const std::string& path)
{
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

enum class InputKind { Mesh, Points, Curves, Grids };

InputKind
inputKind(const std::string& path)
{
    const std::string ext = extensionOf(path);
    if (ext == ".obj" || ext == ".ply" || ext == ".stl") return InputKind::Mesh;
    if (ext == ".csv" || ext == ".xyz" || ext == ".txt") return InputKind::Points;
    if (ext == ".polyline") return InputKind::Curves;
    if (ext == ".vdb") return InputKind::Grids;
    throw UsageError("apply: cannot tell what '" + path +
                     "' holds from its extension (meshes: .obj .ply .stl; points: .csv .xyz "
                     ".txt; 2D curves: .polyline; grids: .vdb)");
}

ApplyCliOptions
parseApplyOptions(int argc, const char* const* argv, int first)
{
    ApplyCliOptions o;
    const std::vector<std::string> positional =
        parseOptions(applyOptionTable(), argc, argv, first, o);
    if (positional.size() != 2) {
        throw UsageError("apply expects DEFORMATION.vdb INPUT, got " +
                         std::to_string(positional.size()) +
                         " file argument(s) (see vdb_match apply --help)");
    }
    o.deformation = positional[0];
    o.input = positional[1];
    if (o.output.empty()) throw UsageError("apply: missing the output file: -o OUTPUT");
    if (extensionOf(o.deformation) != ".vdb") {
        throw UsageError("apply: the deformation must be a .vdb file (deformation.vdb of match), "
                         "got '" +
                         o.deformation + "'");
    }
    const InputKind kind = inputKind(o.input);
    if (extensionOf(o.output) != extensionOf(o.input)) {
        throw UsageError("apply: the output must have the input's format (" + extensionOf(o.input) +
                         "), got '" + o.output + "'");
    }
    if (o.attributes && (kind != InputKind::Mesh || extensionOf(o.input) != ".ply")) {
        throw UsageError("--attributes needs a PLY mesh input (OBJ, STL and point files have no "
                         "per-vertex properties)");
    }
    if (!o.target.empty() && !o.attributes) {
        throw UsageError("--target is used for the residual attribute: add --attributes");
    }
    if (!o.grid.empty() && kind != InputKind::Grids) {
        throw UsageError("--grid applies to .vdb inputs only");
    }
    std::error_code ec;
    if (fs::equivalent(o.output, o.input, ec) || fs::equivalent(o.output, o.deformation, ec)) {
        throw UsageError("apply: the output '" + o.output +
                         "' would overwrite an input; choose another file");
    }
    return o;
}

/// Throws IoError unless @a path is an existing regular file.
void
requireFile(const std::string& path)
{
    std::error_code ec;
    const auto status = fs::status(path, ec);
    if (!fs::exists(status))
        OPENVDB_THROW(openvdb::IoError, "file '" << path << "' does not exist");
    if (fs::is_directory(status))
        OPENVDB_THROW(openvdb::IoError, "'" << path << "' is a directory");
}

/// The signed distance of the --target shape, valid at any world point.
std::function<double(const openvdb::Vec3d&)>
targetDistance(const ApplyCliOptions& o, const DeformationField& phi)
{
    if (o.target.empty()) return {};
    const Shape shape = readShape(o.target);
    if (shape.dim != phi.dimension()) {
        OPENVDB_THROW(openvdb::ValueError, "--target '" << o.target << "' is a " << shape.dim
                                                        << "D shape but the deformation is "
                                                        << phi.dimension() << "D");
    }
    const UnitBoxPlacement omega = eval::domainPlacement(phi);
    const int level = eval::defaultDistanceLevel(shape.dim, eval::deformationLevel(phi));
    if (shape.dim == 2) {
        auto d = std::make_shared<eval::ShapeDistance<2>>(shape.curve, omega, level);
        return [d](const openvdb::Vec3d& x) { return d->signedDistance(x); };
    }
    auto d = std::make_shared<eval::ShapeDistance<3>>(shape.surface, omega, level);
    return [d](const openvdb::Vec3d& x) { return d->signedDistance(x); };
}

/// Throws if inverse walks failed: phi is not invertible where they ended.
void
checkInverseFailures(std::size_t failures, const std::string& what)
{
    if (failures == 0) return;
    OPENVDB_THROW(openvdb::ValueError,
                  "the deformation is not invertible: the exact inverse failed at "
                      << failures << " " << what
                      << " (det D phi <= 0 on a simplex; see vdb_match consistency)");
}

std::string
mapName(const ApplyCliOptions& o)
{
    return o.inverse ? "phi^-1" : "phi";
}

int
applyToMesh(const ApplyCliOptions& o, const DeformationField& phi,
            const std::function<void(const std::string&)>& say, std::ostream& out)
{
    say("reading " + o.input);
    MeshDocument mesh = MeshDocument::read(o.input);
    checkInterrupted();
    MeshTransportOptions options;
    options.inverse = o.inverse;
    options.attributes = o.attributes;
    if (o.attributes) {
        options.signedDistance = targetDistance(o, phi);
        // Faces for the area-weighted normals of area_stretch (PLY keeps its vertex order).
        try {
            const Surface<3> surface = readMesh(o.input);
            if (surface.points.size() == mesh.vertexCount()) options.triangles = surface.elements;
        } catch (const openvdb::ValueError&) {
            // Not a closed mesh (e.g. a point cloud): area_stretch uses the file's normals.
        }
    }
    say("moving " + std::to_string(mesh.vertexCount()) + " vertices by " + mapName(o));
    const MeshTransportResult r = transportMesh(mesh, phi, options);
    checkInverseFailures(r.inverseFailures, "vertices");
    checkInterrupted();
    mesh.write(o.output);
    out << PROGRAM << ": wrote " << o.output << " (" << r.vertices << " vertices and " << r.normals
        << " normals moved by " << mapName(o) << ", max displacement "
        << fixed("%.4g", r.maxDisplacement) << " world units";
    if (r.outsideDomain) out << ", " << r.outsideDomain << " outside the domain left in place";
    if (!r.added.empty()) {
        out << "; attributes";
        for (const std::string& name : r.added)
            out << " " << name;
    }
    out << ")\n";
    return EXIT_OK;
}

int
applyToPoints(const ApplyCliOptions& o, const DeformationField& phi,
              const std::function<void(const std::string&)>& say, std::ostream& out)
{
    say("reading " + o.input);
    PointTable table = PointTable::read(o.input, phi.dimension());
    checkInterrupted();
    std::vector<openvdb::Vec3d> points = table.positions();
    const std::size_t failures = phi.mapPoints(points, o.inverse);
    checkInverseFailures(failures, "points");
    std::size_t outside = 0;
    double maxMove = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const openvdb::Vec3d& p = table.positions()[i];
        for (int a = 0; a < phi.dimension(); ++a) {
            if (p[a] < phi.worldBounds().min()[a] || p[a] > phi.worldBounds().max()[a]) {
                ++outside;
                break;
            }
        }
        maxMove = std::max(maxMove, (points[i] - p).length());
    }
    table.positions() = points;
    checkInterrupted();
    table.write(o.output);
    out << PROGRAM << ": wrote " << o.output << " (" << points.size() << " points moved by "
        << mapName(o) << ", max displacement " << fixed("%.4g", maxMove) << " world units";
    if (outside) out << ", " << outside << " outside the domain left in place";
    out << ")\n";
    return EXIT_OK;
}

int
applyToCurves(const ApplyCliOptions& o, const DeformationField& phi,
              const std::function<void(const std::string&)>& say, std::ostream& out)
{
    if (phi.dimension() != 2) {
        OPENVDB_THROW(openvdb::ValueError,
                      "'" << o.input << "' holds 2D curves but the deformation is 3D");
    }
    say("reading " + o.input);
    Surface<2> curves = readPolyline(o.input);
    checkInterrupted();
    std::vector<openvdb::Vec3d> points(curves.points.size());
    for (std::size_t i = 0; i < points.size(); ++i)
        points[i] = openvdb::Vec3d(curves.points[i][0], curves.points[i][1], 0.0);
    const std::size_t failures = phi.mapPoints(points, o.inverse);
    checkInverseFailures(failures, "curve vertices");
    for (std::size_t i = 0; i < points.size(); ++i)
        curves.points[i] = Vec<2>(points[i][0], points[i][1]);
    checkInterrupted();
    writeFileAtomically(o.output, [&](std::ostream& os) { writePolyline(os, curves); });
    out << PROGRAM << ": wrote " << o.output << " (" << points.size() << " curve vertices moved by "
        << mapName(o) << ")\n";
    return EXIT_OK;
}

int
applyToGrids(const ApplyCliOptions& o, const DeformationField& phi,
             const std::function<void(const std::string&)>& say, std::ostream& out)
{
    say("reading " + o.input);
    requireFile(o.input);
    // Lengths, counts and offsets against the file size before OpenVDB allocates from them.
    checkVdbFileStructure(o.input, "'" + o.input + "'");
    openvdb::GridPtrVecPtr grids;
    openvdb::MetaMap::Ptr fileMeta;
    try {
        openvdb::io::File file(o.input);
        file.open(false);
        grids = file.getGrids();
        fileMeta = file.getMetadata();
        file.close();
    } catch (const std::exception& e) {
        OPENVDB_THROW(openvdb::IoError, "'" << o.input << "' cannot be read as a VDB file ("
                                            << oneLine(e.what()) << ")");
    }
    std::vector<openvdb::GridBase::Ptr> selected;
    for (const openvdb::GridBase::Ptr& g : *grids) {
        if (o.grid.empty() || g->getName() == o.grid) selected.push_back(g);
    }
    if (selected.empty()) {
        std::string names;
        for (const openvdb::GridBase::Ptr& g : *grids)
            names += (names.empty() ? "'" : ", '") + g->getName() + "'";
        if (o.grid.empty()) {
            OPENVDB_THROW(openvdb::ValueError, "'" << o.input << "' holds no grid");
        }
        OPENVDB_THROW(openvdb::ValueError, "'" << o.input << "' has no grid named '" << o.grid
                                               << "' (grids: " << names << ")");
    }
    for (const openvdb::GridBase::Ptr& g : selected) {
        if (!isTransportableGrid(*g)) {
            OPENVDB_THROW(openvdb::TypeError,
                          "grid '" << g->getName() << "' of '" << o.input << "' holds "
                                   << g->valueType()
                                   << " values, which apply cannot carry (float, double, vec3s, "
                                      "vec3d); choose the others with --grid NAME");
        }
    }
    SignalInterrupter interrupter;
    openvdb::GridPtrVec carried;
    std::string summary;
    for (const openvdb::GridBase::Ptr& g : selected) {
        const bool levelSet =
            g->isType<openvdb::FloatGrid>() && g->getGridClass() == openvdb::GRID_LEVEL_SET;
        say("carrying grid '" + g->getName() + "' by " + mapName(o) +
            (levelSet ? " (level set: its surface is moved and the distance rebuilt)"
                      : " (field: resampled at " + (o.inverse ? std::string("phi") : "phi^-1") +
                            " of each output voxel)"));
        const Clock::time_point t0 = Clock::now();
        GridTransportResult r = transportGrid(*g, phi, o.inverse, true, &interrupter);
        if (!r.grid) throw Interrupted{};
        checkInverseFailures(r.inverseFailures, "voxels of grid '" + g->getName() + "'");
        r.grid->insertMeta("vdbmatch_deformation", openvdb::StringMetadata(o.deformation));
        r.grid->insertMeta("vdbmatch_direction",
                           openvdb::StringMetadata(o.inverse ? "inverse" : "forward"));
        say("  " + std::to_string(r.points) +
            (r.levelSet ? " surface vertices moved" : " voxels evaluated") + ", " +
            std::to_string(r.grid->activeVoxelCount()) + " active voxels, " +
            fixed("%.1f", secondsSince(t0)) + " s");
        summary += (summary.empty() ? "" : ", ") + g->getName() +
                   (r.levelSet ? " (level set rebuilt)" : " (resampled)");
        carried.push_back(r.grid);
    }
    checkInterrupted();
    writeGridsAtomically(o.output, carried, fileMeta ? *fileMeta : openvdb::MetaMap());
    out << PROGRAM << ": wrote " << o.output << " (grids " << summary << ", by " << mapName(o)
        << ")\n";
    return EXIT_OK;
}

} // namespace

std::string
applyOptionHelp()
{
    return optionHelp(applyOptionTable());
}

std::vector<OptionDescription>
applyOptionDescriptions()
{
    return describeOptions(applyOptionTable());
}

std::string
applyHelpText()
{
    std::string s;
    s += "Usage: vdb_match apply DEFORMATION.vdb INPUT -o OUTPUT [--inverse] [options]\n\n";
    s += "Carries INPUT through the deformation phi of DEFORMATION.vdb (deformation.vdb of "
         "'vdb_match match',\nwhich maps the source space onto the target space), or through "
         "its exact inverse with --inverse.\n\n";
    s += "What moves where:\n";
    s += wrapHelp("meshes .obj .ply .stl",
                  "every vertex x goes to phi(x); normals are carried by the cofactor of D phi "
                  "and renormalised; faces, quads, UVs, groups, colours and other properties are "
                  "kept byte for byte");
    s += wrapHelp("points .csv .xyz .txt",
                  "a header names the columns; x, y (and z) are moved, other columns kept");
    s += wrapHelp("2D curves .polyline",
                  "(with a 2D deformation) every vertex moved; written one block per curve");
    s += wrapHelp(".vdb grids",
                  "a level set is carried as its surface and rebuilt as a signed distance on "
                  "its own transform; any other float, double or vector grid f becomes "
                  "g(y) = f(phi^-1(y)) (with --inverse g(x) = f(phi(x))): values move with the "
                  "points, unscaled");
    s += wrapHelp("outside the domain", "points outside the deformation's box stay in place");
    s += "\nOptions, as --name VALUE or --name=VALUE.\n";
    s += applyOptionHelp();
    s += "\nExit codes: 0 success, 1 usage error, 2 missing or unreadable file, 3 invalid input "
         "(not a\ndeformation grid, unsupported grid type, a fold where the inverse is needed), 5 "
         "interrupted.\nOn any error no output file is written. See docs/apply.md.\n";
    return s;
}

int
runApplyCommand(int argc, const char* const* argv, int first, std::ostream& out, std::ostream& err)
{
    const ApplyCliOptions o = parseApplyOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    std::optional<tbb::global_control> threadLimit;
    if (o.threads > 0) {
        threadLimit.emplace(tbb::global_control::max_allowed_parallelism, size_t(o.threads));
    }
    auto say = [&](const std::string& text) {
        if (!o.quiet) err << PROGRAM << ": " << text << std::endl;
    };
    requireFile(o.deformation);
    requireFile(o.input);
    say("reading " + o.deformation);
    const DeformationField phi = DeformationField::read(o.deformation);
    if (auto m = phi.grid().getMetadata<openvdb::BoolMetadata>(INVERSE_METADATA)) {
        if (m->value()) {
            say("note: '" + o.deformation +
                "' is an inverse grid; its map is sampled at the nodes (O(h^2) between them). "
                "The exact inverse is 'apply deformation.vdb INPUT --inverse'");
        }
    }
    checkInterrupted();
    switch (inputKind(o.input)) {
    case InputKind::Mesh:
        return applyToMesh(o, phi, say, out);
    case InputKind::Points:
        return applyToPoints(o, phi, say, out);
    case InputKind::Curves:
        return applyToCurves(o, phi, say, out);
    case InputKind::Grids:
        break;
    }
    return applyToGrids(o, phi, say, out);
}

} // namespace cli
} // namespace vdbmatch
