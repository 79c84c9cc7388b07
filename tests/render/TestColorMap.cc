/// @file TestColorMap.cc
/// @brief Colour maps: inferno's end colours match matplotlib's table and its luminance
///        increases monotonically; the diverging map is blue / near-white / red at lo / mid / hi;
///        clamping, NaN grey, and a degenerate range.
#include <vdbmatch/render/ColorMap.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace vdbmatch;

namespace {

double
linear(std::uint8_t c)
{
    const double v = c / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

/// Relative luminance (Rec. 709 primaries) of an sRGB colour.
double
luminance(const Rgb8& c)
{
    return 0.2126 * linear(c[0]) + 0.7152 * linear(c[1]) + 0.0722 * linear(c[2]);
}

} // namespace

TEST(ColorMap, InfernoEndpoints)
{
    // matplotlib _inferno_data[0] = (0.001462, 0.000466, 0.013866), [255] = (0.988362, 0.998364,
    // 0.644924), times 255 and rounded.
    EXPECT_EQ(colorMapAt(0.0, ColorMapKind::Inferno), (Rgb8{0, 0, 4}));
    EXPECT_EQ(colorMapAt(1.0, ColorMapKind::Inferno), (Rgb8{252, 255, 164}));
    EXPECT_EQ(mapValue(-5.0, -1.0, 3.0, ColorMapKind::Inferno), (Rgb8{0, 0, 4}));
    EXPECT_EQ(mapValue(7.0, -1.0, 3.0, ColorMapKind::Inferno), (Rgb8{252, 255, 164}));
}

TEST(ColorMap, InfernoLuminanceIncreases)
{
    double previous = -1.0;
    for (int i = 0; i <= 1000; ++i) {
        const double l = luminance(colorMapAt(i / 1000.0, ColorMapKind::Inferno));
        // One 8-bit rounding step of slack.
        EXPECT_GE(l, previous - 2e-3) << "t = " << i / 1000.0;
        previous = std::max(previous, l);
    }
    EXPECT_GT(luminance(colorMapAt(1.0, ColorMapKind::Inferno)), 0.9);
    EXPECT_LT(luminance(colorMapAt(0.0, ColorMapKind::Inferno)), 0.01);
}

TEST(ColorMap, DivergingBlueWhiteRed)
{
    const Rgb8 low = mapValue(-2.0, -2.0, 2.0, ColorMapKind::Diverging);
    const Rgb8 mid = mapValue(0.0, -2.0, 2.0, ColorMapKind::Diverging);
    const Rgb8 high = mapValue(2.0, -2.0, 2.0, ColorMapKind::Diverging);
    EXPECT_GT(low[2], low[0] + 50);
    EXPECT_GT(high[0], high[2] + 50);
    for (int k = 0; k < 3; ++k)
        EXPECT_GE(mid[k], 240);
    // Lightness falls off on both sides of the middle.
    const double l0 = luminance(mid);
    EXPECT_GT(l0, luminance(mapValue(-1.0, -2.0, 2.0, ColorMapKind::Diverging)));
    EXPECT_GT(l0, luminance(mapValue(1.0, -2.0, 2.0, ColorMapKind::Diverging)));
}

TEST(ColorMap, NonFiniteAndDegenerate)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(mapValue(nan, 0.0, 1.0, ColorMapKind::Inferno), NAN_COLOR);
    EXPECT_EQ(mapValue(inf, 0.0, 1.0, ColorMapKind::Diverging), NAN_COLOR);
    EXPECT_EQ(colorMapAt(nan, ColorMapKind::Inferno), NAN_COLOR);
    EXPECT_EQ(mapValue(3.0, 1.0, 1.0, ColorMapKind::Inferno),
              colorMapAt(0.5, ColorMapKind::Inferno));
}
