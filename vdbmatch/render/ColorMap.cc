/// @file ColorMap.cc
/// @brief The colour-map tables and their interpolation.
#include "ColorMap.h"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace vdbmatch {

namespace {

struct ControlPoint
{
    double t, r, g, b;
};

/// Inferno, by Nathaniel J. Smith and Stefan van der Walt (2015, CC0), as published in
/// matplotlib's lib/matplotlib/_cm_listed.py (_inferno_data, 256 entries): every eighth entry
/// (0, 8, ..., 248) and the last (255), at t = index / 255. Linear interpolation between these
/// 33 points differs from the 256-entry table by less than one 8-bit level in most places.
constexpr ControlPoint INFERNO[] = {
    {0.0 / 255, 0.001462, 0.000466, 0.013866},   {8.0 / 255, 0.013995, 0.011225, 0.071862},
    {16.0 / 255, 0.042253, 0.028139, 0.141141},  {24.0 / 255, 0.081962, 0.043328, 0.215289},
    {32.0 / 255, 0.129285, 0.047293, 0.290788},  {40.0 / 255, 0.183429, 0.040329, 0.354971},
    {48.0 / 255, 0.238273, 0.036621, 0.396353},  {56.0 / 255, 0.290763, 0.045644, 0.418637},
    {64.0 / 255, 0.341500, 0.062325, 0.429425},  {72.0 / 255, 0.391453, 0.080927, 0.433109},
    {80.0 / 255, 0.441207, 0.099338, 0.431594},  {88.0 / 255, 0.491022, 0.117179, 0.425552},
    {96.0 / 255, 0.540920, 0.134729, 0.415123},  {104.0 / 255, 0.590734, 0.152563, 0.400290},
    {112.0 / 255, 0.640135, 0.171438, 0.381065}, {120.0 / 255, 0.688653, 0.192239, 0.357603},
    {128.0 / 255, 0.735683, 0.215906, 0.330245}, {136.0 / 255, 0.780517, 0.243327, 0.299523},
    {144.0 / 255, 0.822386, 0.275197, 0.266085}, {152.0 / 255, 0.860533, 0.311892, 0.230606},
    {160.0 / 255, 0.894305, 0.353399, 0.193584}, {168.0 / 255, 0.923215, 0.399359, 0.155193},
    {176.0 / 255, 0.946965, 0.449191, 0.115272}, {184.0 / 255, 0.965397, 0.502249, 0.073859},
    {192.0 / 255, 0.978422, 0.557937, 0.034931}, {200.0 / 255, 0.985952, 0.615750, 0.025592},
    {208.0 / 255, 0.987874, 0.675267, 0.065257}, {216.0 / 255, 0.984075, 0.736087, 0.129527},
    {224.0 / 255, 0.974638, 0.797692, 0.206332}, {232.0 / 255, 0.960626, 0.859069, 0.298010},
    {240.0 / 255, 0.947594, 0.917399, 0.410665}, {248.0 / 255, 0.954529, 0.965896, 0.540361},
    {255.0 / 255, 0.988362, 0.998364, 0.644924},
};

/// Diverging blue-white-red: ColorBrewer "RdBu" with 11 classes (Cynthia A. Brewer,
/// colorbrewer2.org, Apache-2.0 licence; the same values as matplotlib's _RdBu_data in
/// lib/matplotlib/_cm.py), reversed so that low (negative) values are blue, at equal spacing
/// t = i / 10. Hex: 053061 2166ac 4393c3 92c5de d1e5f0 f7f7f7 fddbc7 f4a582 d6604d b2182b 67001f.
constexpr ControlPoint DIVERGING[] = {
    {0.0, 0x05 / 255.0, 0x30 / 255.0, 0x61 / 255.0},
    {0.1, 0x21 / 255.0, 0x66 / 255.0, 0xac / 255.0},
    {0.2, 0x43 / 255.0, 0x93 / 255.0, 0xc3 / 255.0},
    {0.3, 0x92 / 255.0, 0xc5 / 255.0, 0xde / 255.0},
    {0.4, 0xd1 / 255.0, 0xe5 / 255.0, 0xf0 / 255.0},
    {0.5, 0xf7 / 255.0, 0xf7 / 255.0, 0xf7 / 255.0},
    {0.6, 0xfd / 255.0, 0xdb / 255.0, 0xc7 / 255.0},
    {0.7, 0xf4 / 255.0, 0xa5 / 255.0, 0x82 / 255.0},
    {0.8, 0xd6 / 255.0, 0x60 / 255.0, 0x4d / 255.0},
    {0.9, 0xb2 / 255.0, 0x18 / 255.0, 0x2b / 255.0},
    {1.0, 0x67 / 255.0, 0x00 / 255.0, 0x1f / 255.0},
};

template <size_t N>
Rgb8
interpolate(const ControlPoint (&table)[N], double t)
{
    const ControlPoint* hi =
        std::lower_bound(std::begin(table), std::end(table), t,
                         [](const ControlPoint& p, double value) { return p.t < value; });
    if (hi == std::begin(table)) hi = std::begin(table) + 1;
    if (hi == std::end(table)) hi = std::end(table) - 1;
    const ControlPoint* lo = hi - 1;
    const double s = std::clamp((t - lo->t) / (hi->t - lo->t), 0.0, 1.0);
    auto channel = [s](double a, double b) {
        return static_cast<std::uint8_t>(std::lround(255.0 * ((1.0 - s) * a + s * b)));
    };
    return {channel(lo->r, hi->r), channel(lo->g, hi->g), channel(lo->b, hi->b)};
}

} // namespace

Rgb8
colorMapAt(double t, ColorMapKind kind)
{
    if (std::isnan(t)) return NAN_COLOR;
    t = std::clamp(t, 0.0, 1.0);
    switch (kind) {
    case ColorMapKind::Inferno:
        return interpolate(INFERNO, t);
    case ColorMapKind::Diverging:
        return interpolate(DIVERGING, t);
    }
    return NAN_COLOR;
}

Rgb8
mapValue(double value, double lo, double hi, ColorMapKind kind)
{
    if (!std::isfinite(value)) return NAN_COLOR;
    if (!(hi != lo) || !std::isfinite(hi - lo)) return colorMapAt(0.5, kind);
    return colorMapAt((value - lo) / (hi - lo), kind);
}

const char*
colorMapName(ColorMapKind kind)
{
    switch (kind) {
    case ColorMapKind::Inferno:
        return "inferno";
    case ColorMapKind::Diverging:
        return "diverging";
    }
    return "unknown";
}

} // namespace vdbmatch
