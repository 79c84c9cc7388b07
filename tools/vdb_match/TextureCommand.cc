/// @file TextureCommand.cc
/// @brief `vdb_match texture`: a pattern painted on M1 and carried by phi and psi o phi, written
///        as coloured PLY meshes (3D) or OBJ polylines (2D) and PNG pictures (docs/cli.md).
#include "Cli.h"
#include "CliSupport.h"

#include <vdbmatch/eval/TransportedTexture.h>
#include <vdbmatch/io/AtomicFile.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/io/PlyWriter.h>
#include <vdbmatch/io/ShapeIO.h>
#include <vdbmatch/render/BitmapFont.h>
#include <vdbmatch/render/Curves2D.h>
#include <vdbmatch/render/Rasterizer.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {
namespace cli {

namespace {

/// Options of `texture`.
struct TextureCliOptions
{
    std::string phi;     ///< PHI.vdb (positional)
    std::string source;  ///< --source M1
    std::string inverse; ///< --inverse PSI.vdb
    std::string target;  ///< --target M2
    std::string outDir;  ///< -o, --output
    std::string pattern = "checker";
    int bands = 12; ///< --bands: cells around the pole axis / along the curve
    int axis = 1;   ///< --axis: pole or stripe axis
    int size = 400; ///< --size: pixels per view / panel
    int cells = DEFAULT_GRID_CELLS;
    bool quiet = false;
};

/// Title strip height, text scale and colours of the pictures.
constexpr int TITLE_SCALE = 2;
constexpr int TITLE_PADDING_PX = 6;
constexpr Rgb8 TITLE_COLOR{20, 20, 20};
constexpr Rgb8 SEPARATOR{160, 160, 160};
constexpr Rgb8 WHITE{255, 255, 255};
/// The reference curve (M2, or M1 under the round trip) in 2D pictures: thin and dark.
constexpr Rgb8 REFERENCE_COLOR{60, 60, 60};
constexpr double REFERENCE_WIDTH_PX = 1.5;
/// Smallest --size that leaves room for the labels.
constexpr int MIN_SIZE_PX = 64;

std::vector<Option<TextureCliOptions>>
textureOptionTable()
{
    const TextureCliOptions d;
    using O = TextureCliOptions;
    // clang-format off
    return {
        {"--source", "M1", "Input", "the source shape M1 that phi was computed for (required)",
         [](O& o, const std::string& v) { o.source = v; }},
        {"--inverse", "PSI.vdb", "Input",
         "deformation.vdb of the reverse matching (M2 onto M1): also draw psi(phi(M1))",
         [](O& o, const std::string& v) { o.inverse = v; }},
        {"--target", "M2", "Input", "the target shape M2, drawn for comparison",
         [](O& o, const std::string& v) { o.target = v; }},
        {"--output,-o", "OUTDIR", "Output", "output directory, created if needed (required)",
         [](O& o, const std::string& v) { o.outDir = v; }},
        {"--pattern", "NAME", "Pattern",
         "checker, stripes or position (default " + d.pattern + "); see docs/cli.md",
         [](O& o, const std::string& v) {
             if (v != "checker" && v != "stripes" && v != "position") {
                 throw UsageError("--pattern expects 'checker', 'stripes' or 'position', got '" +
                                  v + "'");
             }
             o.pattern = v;
         }},
        {"--bands", "N", "Pattern",
         "checker: cells around the pole axis (N/2 from pole to pole; 2D: sectors around the "
         "centre); stripes: bands across M1 along --axis (2D: along the curve), >= 2 (default " +
             std::to_string(d.bands) + ")",
         [](O& o, const std::string& v) { o.bands = parseInt("--bands", v); }},
        {"--axis", "x|y|z", "Pattern", "3D pole axis (checker) or stripe axis (default y)",
         [](O& o, const std::string& v) {
             if (v != "x" && v != "y" && v != "z") {
                 throw UsageError("--axis expects x, y or z, got '" + v + "'");
             }
             o.axis = v[0] - 'x';
         }},
        {"--size", "PX", "Output",
         "pixels per view and per panel, >= " + std::to_string(MIN_SIZE_PX) + " (default " +
             std::to_string(d.size) + ")",
         [](O& o, const std::string& v) { o.size = parseInt("--size", v); }},
        {"--grid-cells", "N", "Output",
         "2D: grid cells across Omega in each direction, 1..512 (default " +
             std::to_string(d.cells) + ")",
         [](O& o, const std::string& v) { o.cells = parseInt("--grid-cells", v); }},
        {"--quiet", nullptr, "Output", "no progress messages on stderr",
         [](O& o, const std::string&) { o.quiet = true; }},
    };
    // clang-format on
}

constexpr int MAX_GRID_CELLS = 512;

TextureCliOptions
parseTextureOptions(int argc, const char* const* argv, int first)
{
    TextureCliOptions o;
    const std::vector<std::string> positional =
        parseOptions(textureOptionTable(), argc, argv, first, o);
    if (positional.size() != 1) {
        throw UsageError("texture expects PHI.vdb, got " + std::to_string(positional.size()) +
                         " file argument(s) (see vdb_match --help)");
    }
    o.phi = positional[0];
    if (o.source.empty()) throw UsageError("texture: missing the source shape: --source M1");
    if (o.outDir.empty()) throw UsageError("missing the output directory: -o OUTDIR");
    if (o.bands < 2) throw UsageError("--bands must be >= 2");
    if (o.size < MIN_SIZE_PX) {
        throw UsageError("--size must be >= " + std::to_string(MIN_SIZE_PX));
    }
    if (o.cells < 1 || o.cells > MAX_GRID_CELLS) {
        throw UsageError("--grid-cells must be in 1.." + std::to_string(MAX_GRID_CELLS));
    }
    return o;
}

////////////////////////////////////////////////////////////////////////////////
// Pictures

/// @a image below a white strip with @a title centred in it.
Image8
titled(const Image8& image, const std::string& title)
{
    const int strip = textHeight(TITLE_SCALE) + 2 * TITLE_PADDING_PX;
    Image8 out(image.width, image.height + strip, WHITE);
    const int x = std::max(0, (image.width - textWidth(title, TITLE_SCALE)) / 2);
    drawText(out, x, TITLE_PADDING_PX, title, TITLE_COLOR, TITLE_SCALE);
    paste(out, image, 0, strip);
    return out;
}

/// The images side by side, separated by one-pixel grey lines.
Image8
row(const std::vector<Image8>& images)
{
    int width = 0, height = 0;
    for (const Image8& image : images) {
        width += image.width;
        height = std::max(height, image.height);
    }
    width += int(images.size()) - 1;
    Image8 out(width, height, SEPARATOR);
    int x = 0;
    for (const Image8& image : images) {
        fillRect(out, x, 0, x + image.width, height, WHITE);
        paste(out, image, x, 0);
        x += image.width + 1;
    }
    return out;
}

void
savePng(const std::string& path, const Image8& image)
{
    writePng(path, image.width, image.height, image.rgb);
}

openvdb::BBoxd
boundsOf(const std::vector<const std::vector<openvdb::Vec3d>*>& sets)
{
    openvdb::BBoxd box;
    for (const auto* points : sets) {
        for (const openvdb::Vec3d& p : *points)
            box.expand(p);
    }
    return box;
}

std::vector<openvdb::Vec3d>
toVec3(const Surface<3>& surface)
{
    std::vector<openvdb::Vec3d> points;
    points.reserve(surface.points.size());
    for (const Vec<3>& p : surface.points)
        points.emplace_back(p[0], p[1], p[2]);
    return points;
}

/// Closed loops as a Surface<2> (points in loop order, segments joining them).
Surface<2>
toSurface(const std::vector<ColoredPolyline2D>& loops)
{
    Surface<2> s;
    for (const ColoredPolyline2D& loop : loops) {
        const auto first = std::int32_t(s.points.size());
        const auto n = std::int32_t(loop.points.size());
        for (std::int32_t i = 0; i < n; ++i) {
            s.points.push_back(Vec<2>(loop.points[i].x(), loop.points[i].y()));
            s.elements.push_back({first + i, first + (i + 1) % n});
        }
    }
    return s;
}

std::vector<ColoredPolyline2D>
referenceCurves(const Surface<2>& curve)
{
    std::vector<ColoredPolyline2D> out;
    for (const auto& loop : closedLoops(curve)) {
        ColoredPolyline2D line;
        for (std::int32_t v : loop)
            line.points.emplace_back(curve.points[v][0], curve.points[v][1]);
        line.colors.assign(line.points.size(), REFERENCE_COLOR);
        line.widthPx = REFERENCE_WIDTH_PX;
        out.push_back(std::move(line));
    }
    return out;
}

////////////////////////////////////////////////////////////////////////////////
// The command

int
runTexture(const TextureCliOptions& o, std::ostream& out, std::ostream& err)
{
    auto progress = [&](const std::string& message) {
        if (!o.quiet) err << PROGRAM << ": " << message << std::endl;
    };
    progress("reading " + o.phi);
    const DeformationField phi = DeformationField::read(o.phi);
    std::optional<DeformationField> psi;
    if (!o.inverse.empty()) {
        progress("reading " + o.inverse);
        psi.emplace(DeformationField::read(o.inverse));
    }
    progress("reading " + o.source);
    const Shape source = readShape(o.source);
    std::optional<Shape> target;
    if (!o.target.empty()) {
        progress("reading " + o.target);
        target.emplace(readShape(o.target));
    }
    checkInterrupted();
    const int dim = phi.dimension();
    auto requireDim = [&](int d, const std::string& what) {
        if (d != dim) {
            OPENVDB_THROW(openvdb::ValueError, "texture: " << what << " is " << d << "D but "
                                                           << o.phi << " is a " << dim
                                                           << "D deformation");
        }
    };
    requireDim(source.dim, "the source '" + o.source + "'");
    if (target) requireDim(target->dim, "the target '" + o.target + "'");
    if (psi) requireDim(psi->dimension(), "the inverse '" + o.inverse + "'");

    namespace fs = std::filesystem;
    createOutputDirectory(o.outDir);
    auto path = [&](const std::string& name) { return (fs::path(o.outDir) / name).string(); };
    std::vector<std::string> written;
    auto wrote = [&](const std::string& name) { written.push_back(path(name)); };
    const std::string comment = "vdb_match texture: pattern " + o.pattern + " on " + o.source;

    if (dim == 3) {
        SurfaceTexture texture;
        texture.axis = o.axis;
        if (o.pattern == "checker") {
            texture.pattern = SurfacePattern::Checker;
            texture.longitudeCells = o.bands;
            texture.latitudeCells = std::max(1, o.bands / 2);
        } else if (o.pattern == "stripes") {
            texture.pattern = SurfacePattern::AxisStripes;
            const openvdb::BBoxd box = boundingBox(source.surface);
            texture.stripeWidth = box.extents()[o.axis] / o.bands;
        } else {
            texture.pattern = SurfacePattern::Position;
        }
        progress("carrying the texture by phi" + std::string(psi ? " and psi o phi" : ""));
        const TransportedSurface t =
            transportSurface(source.surface, texture, phi, psi ? &*psi : nullptr);
        checkInterrupted();

        auto ply = [&](const std::string& name, const std::vector<openvdb::Vec3d>& points,
                       const std::string& what) {
            writeFileAtomically(path(name), [&](std::ostream& os) {
                writePly(os, points, t.triangles, t.colors, PlyFormat::BinaryLittleEndian,
                         comment + "\n" + what);
            });
            wrote(name);
        };
        progress("writing " + o.outDir);
        ply("source.ply", t.source, "M1");
        ply("deformed.ply", t.deformed, "phi(M1), phi = " + o.phi);
        if (psi) ply("roundtrip.ply", t.roundtrip, "psi(phi(M1)), psi = " + o.inverse);

        std::vector<openvdb::Vec3d> targetPoints;
        if (target) targetPoints = toVec3(target->surface);
        const openvdb::BBoxd sourceFrame =
            boundsOf(psi ? std::vector<const std::vector<openvdb::Vec3d>*>{&t.source, &t.roundtrip}
                         : std::vector<const std::vector<openvdb::Vec3d>*>{&t.source});
        const openvdb::BBoxd deformedFrame = boundsOf({&t.deformed, &targetPoints});
        const auto& tris = t.triangles;
        savePng(path("source.png"),
                titled(renderViews(t.source, tris, t.colors, sourceFrame, o.size), "SOURCE M1"));
        wrote("source.png");
        savePng(path("deformed.png"),
                titled(renderViews(t.deformed, tris, t.colors, deformedFrame, o.size), "PHI(M1)"));
        wrote("deformed.png");
        if (psi) {
            savePng(path("roundtrip.png"),
                    titled(renderViews(t.roundtrip, tris, t.colors, sourceFrame, o.size),
                           "PSI(PHI(M1))"));
            wrote("roundtrip.png");
        }
        if (target) {
            savePng(path("target.png"), titled(renderViews(targetPoints, target->surface.elements,
                                                           {}, deformedFrame, o.size),
                                               "TARGET M2"));
            wrote("target.png");
        }
        // Summary: one 3/4 view per shape, all framed alike.
        openvdb::BBoxd all = sourceFrame;
        all.expand(deformedFrame);
        const Camera camera = standardViewCamera(all, StandardView::ThreeQuarter);
        std::vector<Image8> panels;
        panels.push_back(
            titled(renderMesh(t.source, tris, t.colors, camera, o.size, o.size), "M1"));
        if (target) {
            panels.push_back(titled(
                renderMesh(targetPoints, target->surface.elements, {}, camera, o.size, o.size),
                "M2"));
        }
        panels.push_back(
            titled(renderMesh(t.deformed, tris, t.colors, camera, o.size, o.size), "PHI(M1)"));
        if (psi) {
            panels.push_back(titled(renderMesh(t.roundtrip, tris, t.colors, camera, o.size, o.size),
                                    "PSI(PHI(M1))"));
        }
        savePng(path("summary.png"), row(panels));
        wrote("summary.png");
    } else {
        CurveTexture texture;
        if (o.pattern == "checker") {
            texture.pattern = CurvePattern::AngleStripes;
            texture.angleCells = o.bands;
        } else if (o.pattern == "stripes") {
            texture.pattern = CurvePattern::ArcLengthStripes;
            texture.stripeWidth = measure(source.curve) / o.bands;
        } else {
            texture.pattern = CurvePattern::Position;
        }
        progress("carrying the texture and a " + std::to_string(o.cells) + "x" +
                 std::to_string(o.cells) + " grid by phi" +
                 std::string(psi ? " and psi o phi" : ""));
        const TransportedCurve t =
            transportCurve(source.curve, texture, phi, psi ? &*psi : nullptr, o.cells);
        checkInterrupted();

        progress("writing " + o.outDir);
        auto obj = [&](const std::string& name, const std::vector<ColoredPolyline2D>& loops) {
            const Surface<2> s = toSurface(loops);
            writeFileAtomically(path(name), [&](std::ostream& os) { writeObj(os, s); });
            wrote(name);
        };
        obj("deformed.obj", t.deformed);
        if (psi) obj("roundtrip.obj", t.roundtrip);

        // All pictures frame Omega, like the paper's fig:jump. The reference curve is drawn
        // first (under the coloured one): M2 for source and phi(M1), M1 for the round trip.
        const std::vector<ColoredPolyline2D> targetRef =
            target ? referenceCurves(target->curve) : std::vector<ColoredPolyline2D>{};
        const std::vector<ColoredPolyline2D> sourceRef = referenceCurves(source.curve);
        auto picture = [&](const std::vector<ColoredPolyline2D>& reference,
                           const std::vector<ColoredPolyline2D>& curves,
                           const std::vector<std::vector<openvdb::Vec2d>>& grid,
                           const std::string& title) {
            std::vector<ColoredPolyline2D> all = reference;
            all.insert(all.end(), curves.begin(), curves.end());
            return titled(renderCurves2D(all, grid, t.omegaMin, t.omegaMax, o.size, o.size), title);
        };
        std::vector<Image8> panels;
        panels.push_back(picture(targetRef, t.source, t.grid, target ? "M1 AND M2" : "SOURCE M1"));
        savePng(path("source.png"), panels.back());
        wrote("source.png");
        panels.push_back(picture(targetRef, t.deformed, t.deformedGrid, "PHI(M1)"));
        savePng(path("deformed.png"), panels.back());
        wrote("deformed.png");
        if (psi) {
            panels.push_back(picture(sourceRef, t.roundtrip, t.roundtripGrid, "PSI(PHI(M1))"));
            savePng(path("roundtrip.png"), panels.back());
            wrote("roundtrip.png");
        }
        savePng(path("summary.png"), row(panels));
        wrote("summary.png");
    }
    for (const std::string& file : written)
        out << file << "\n";
    out.flush();
    return EXIT_OK;
}

} // namespace

std::string
textureOptionHelp()
{
    return optionHelp(textureOptionTable());
}

std::vector<OptionDescription>
textureOptionDescriptions()
{
    return describeOptions(textureOptionTable());
}

int
runTextureCommand(int argc, const char* const* argv, int first, std::ostream& out,
                  std::ostream& err)
{
    const TextureCliOptions options = parseTextureOptions(argc, argv, first);
    openvdb::initialize();
    SignalScope signals;
    return runTexture(options, out, err);
}

} // namespace cli
} // namespace vdbmatch
