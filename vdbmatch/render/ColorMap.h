/// @file ColorMap.h
/// @brief Colour maps from a scalar value to an sRGB colour: inferno (sequential) and a diverging
///        blue-white-red map for signed fields centred at 0.
///
/// Each map is a piecewise-linear table of control points (t in [0, 1], sRGB-encoded channel
/// values in [0, 1]); interpolation is linear in the sRGB-encoded values, as matplotlib does.
/// Sources of the tables are cited in ColorMap.cc.
#pragma once

#include <vdbmatch/render/Canvas.h>

namespace vdbmatch {

enum class ColorMapKind {
    Inferno,  ///< sequential, black -> purple -> orange -> pale yellow; luminance increases
    Diverging ///< blue (low) -> near-white (middle) -> red (high); for signed fields, lo = -hi
};

/// Grey drawn for NaN and infinite values.
constexpr Rgb8 NAN_COLOR = {128, 128, 128};

/// The colour of the map at t in [0, 1] (clamped). A NaN t gives NAN_COLOR.
Rgb8 colorMapAt(double t, ColorMapKind kind);

/// The colour of @a value on a scale from @a lo (t = 0) to @a hi (t = 1); values outside are
/// clamped to the end colours, non-finite values give NAN_COLOR. If hi == lo every finite value
/// gets the middle colour.
Rgb8 mapValue(double value, double lo, double hi, ColorMapKind kind);

/// "inferno" or "diverging".
const char* colorMapName(ColorMapKind kind);

} // namespace vdbmatch
