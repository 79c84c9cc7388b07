/// @file Preview.h
/// @brief A quick-look picture of a 2D scalar field (e.g. a slice of a level set or of det Dphi):
///        the field through a colour map, enlarged, with the zero contours of auxiliary fields
///        (the shapes' outlines) on top, a title, and a colour bar labelled with its numeric range.
///
/// Layout, top to bottom: the title (if any); the field image, enlarged by an integer factor
/// (nearest neighbour, so every field sample is a visible square) until its short side is at
/// least PreviewOptions::minShortSidePx; the colour bar, as wide as the field image, with ticks
/// and labels at lo, (lo + hi) / 2 and hi. White background, dark text (BitmapFont).
///
/// Field layout: width x height floats, row after row, row 0 drawn at the top; sample (x, y) is
/// drawn centred at ((x + 0.5) s, (y + 0.5) s) in the field image, s the enlargement factor.
/// Non-finite samples are drawn in NAN_COLOR (grey). Contours: the zero level of each auxiliary
/// field, found by marching squares on the cells between sample centres (linear interpolation
/// along cell edges, saddles resolved by the cell average; cells with a non-finite corner are
/// skipped), drawn as a thin line in the contour colour over a white halo.
#pragma once

#include <vdbmatch/render/Canvas.h>
#include <vdbmatch/render/ColorMap.h>

#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {

struct PreviewOptions
{
    float lo = 0.0f; ///< value drawn with the first colour
    float hi = 1.0f; ///< value drawn with the last colour
    ColorMapKind colorMap = ColorMapKind::Inferno;
    std::vector<const float*> contourFields; ///< same layout as the field; zero contours drawn
    std::vector<Rgb8> contourColors;         ///< per contour field; missing ones are black
    std::string title;                       ///< drawn above the field (upper case)
    int minShortSidePx = 256;                ///< enlarge until min(width, height) * s >= this
};

/// Renders the preview picture of @a field (@a width x @a height samples).
/// @throw openvdb::ValueError if field or a contour field is null, a size is not positive, or
///        lo / hi are not finite with lo <= hi
Image8 renderFieldPreview(const float* field, int width, int height, const PreviewOptions& options);

/// The smallest and largest finite values among @a count values, or (0, 0) if there are none.
std::pair<float, float> finiteRange(const float* values, size_t count);

/// The tick label for @a value: printf "%.3g", with -0 written as 0.
std::string formatTickLabel(double value);

} // namespace vdbmatch
