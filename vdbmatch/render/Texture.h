/// @file Texture.h
/// @brief Per-vertex colour patterns painted on a source surface (3D) or curve (2D), to be
///        carried along by phi and rendered on the deformed shape: a transported texture shows
///        where each part of the source went.
///
/// Spaces: points are world coordinates (openvdb::Vec3d / Vec2d). The centre of the spherical
/// and angular parametrizations is the vertex average unless given. Patterns alternate between
/// two colours, colorA and colorB, band 0 being colorA, except Position (continuous colours).
/// Points with a non-finite coordinate get grey (128, 128, 128) and are left out of the bounding
/// box and the centroid.
///
/// Surface patterns and their periods:
/// - AxisStripes: slabs perpendicular to world axis @a axis (0 = x, 1 = y, 2 = z); band
///   floor((p[axis] - min over points) / stripeWidth), i.e. period 2 * stripeWidth world units.
/// - LongitudeStripes: longitude bands about the pole axis @a axis through the centre;
///   longitudeCells bands around the full turn (each 360 / longitudeCells degrees).
/// - Checker: longitude x latitude cells about the centre: longitudeCells around, latitudeCells
///   from pole to pole (each 180 / latitudeCells degrees); colour by parity of the sum.
/// - Position: R, G, B = the point's x, y, z normalized to [0, 255] in the points' bounding box
///   (0.5 on a flat axis).
/// Longitude is measured about @a axis, from the next axis ((axis + 1) % 3) towards
/// ((axis + 2) % 3); latitude is the angle above the plane perpendicular to @a axis. An even
/// longitudeCells makes the pattern seamless across the 0/360 degree line.
#pragma once

#include <vdbmatch/render/Canvas.h>

#include <openvdb/Types.h>

#include <optional>
#include <vector>

namespace vdbmatch {

enum class SurfacePattern { AxisStripes, LongitudeStripes, Checker, Position };

struct SurfaceTexture
{
    SurfacePattern pattern = SurfacePattern::Checker;
    int axis = 1;              ///< stripe axis (AxisStripes) or pole axis (spherical), 0..2
    double stripeWidth = 0.1;  ///< AxisStripes: width of one band, world units
    int longitudeCells = 12;   ///< bands around the pole axis
    int latitudeCells = 6;     ///< bands from pole to pole (Checker)
    Rgb8 colorA{230, 120, 30}; ///< orange
    Rgb8 colorB{40, 90, 200};  ///< blue
    std::optional<openvdb::Vec3d> center; ///< centre of the spherical coordinates; default centroid
};

/// One colour per point of a surface.
/// @throw openvdb::ValueError if axis is not 0..2, stripeWidth <= 0 or a cell count < 1
std::vector<Rgb8> paintSurface(const std::vector<openvdb::Vec3d>& points,
                               const SurfaceTexture& texture);

/// Curve patterns (a checker on a curve is a stripe pattern):
/// - ArcLengthStripes: band floor(s / stripeWidth), s the arc length from the first point along
///   the polyline (period 2 * stripeWidth world units);
/// - AngleStripes: angleCells bands around the centre, by the polar angle atan2(y - cy, x - cx);
/// - Position: R, G = x, y normalized in the bounding box, B = 255 - R.
enum class CurvePattern { ArcLengthStripes, AngleStripes, Position };

struct CurveTexture
{
    CurvePattern pattern = CurvePattern::AngleStripes;
    double stripeWidth = 0.1; ///< ArcLengthStripes: band length, world units
    int angleCells = 12;      ///< AngleStripes: bands around the full turn
    Rgb8 colorA{230, 120, 30};
    Rgb8 colorB{40, 90, 200};
    std::optional<openvdb::Vec2d> center; ///< default: the vertex average
};

/// One colour per point of a polyline (ordered along the curve).
/// @throw openvdb::ValueError if stripeWidth <= 0 or angleCells < 1
std::vector<Rgb8> paintCurve(const std::vector<openvdb::Vec2d>& points,
                             const CurveTexture& texture);

} // namespace vdbmatch
