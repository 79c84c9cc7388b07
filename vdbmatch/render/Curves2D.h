/// @file Curves2D.h
/// @brief Drawing 2D curves for the planar problems: closed or open polylines with per-vertex
///        colours as thick lines, over optional thin grey grid lines (e.g. the images of lattice
///        lines under phi), framed to a rectangle of the plane, on a white background.
///
/// Spaces: points are openvdb::Vec2d in world (plane) coordinates, x right and y up. The frame
/// [frameMin, frameMax] is mapped to the image with a uniform scale (aspect ratio kept), centred,
/// with a margin; y is flipped so that +y is drawn upwards. Line widths are in output pixels.
/// Colours along a segment are interpolated between its end points (sRGB bytes).
#pragma once

#include <vdbmatch/render/Canvas.h>

#include <openvdb/Types.h>

#include <vector>

namespace vdbmatch {

/// A polyline with one colour per point (or none: drawn black).
struct ColoredPolyline2D
{
    std::vector<openvdb::Vec2d> points;
    std::vector<Rgb8> colors; ///< empty or one per point
    bool closed = true;       ///< join the last point to the first
    double widthPx = 0.0;     ///< line width, output pixels; <= 0: Curves2DOptions::curveWidthPx
};

struct Curves2DOptions
{
    double curveWidthPx = 3.0;
    double gridWidthPx = 1.0;
    Rgb8 gridColor{175, 175, 175};
    Rgb8 background{255, 255, 255};
    double marginFraction = 0.04; ///< margin on each side, as a fraction of the short side
    bool supersample = true;      ///< draw at 2x2 and box-filter (anti-aliasing)
};

/// Draws @a gridLines (open polylines, grey) and then @a curves into a @a width x @a height image
/// framing the rectangle [frameMin, frameMax].
/// @throw openvdb::ValueError if the size is not positive, the frame is empty or not finite, or
///        a curve's colours are neither empty nor one per point, or marginFraction is not in
///        [0, 0.5)
Image8 renderCurves2D(const std::vector<ColoredPolyline2D>& curves,
                      const std::vector<std::vector<openvdb::Vec2d>>& gridLines,
                      const openvdb::Vec2d& frameMin, const openvdb::Vec2d& frameMax, int width,
                      int height, const Curves2DOptions& options = {});

} // namespace vdbmatch
