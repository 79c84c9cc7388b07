/// @file TestPreview.cc
/// @brief The field preview: size and enlargement, many distinct colours, NaN drawn grey, the
///        zero contour drawn (dark pixels on the circle, none far from it in the field), dark
///        text pixels in the title and colour-bar label areas; the PNG written from it.
#include "support/RenderSupport.h"

#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/render/BitmapFont.h>
#include <vdbmatch/render/Preview.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <unistd.h>

using namespace vdbmatch;

namespace {

constexpr int W = 64, H = 48;

/// Signed distance, in samples, to a circle of radius @a r about (cx, cy).
std::vector<float>
circle(double cx, double cy, double r)
{
    std::vector<float> f(W * H);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x)
            f[y * W + x] = float(std::hypot(x - cx, y - cy) - r);
    }
    return f;
}

bool
isDark(const Rgb8& c)
{
    return c[0] < 70 && c[1] < 70 && c[2] < 70;
}

/// Counts dark pixels in rows [y0, y1).
int
darkPixelsInRows(const Image8& image, int y0, int y1)
{
    int n = 0;
    for (int y = std::max(0, y0); y < std::min(y1, image.height); ++y) {
        for (int x = 0; x < image.width; ++x)
            n += isDark(image.at(x, y));
    }
    return n;
}

} // namespace

TEST(Preview, FieldContoursAndColourBar)
{
    std::vector<float> field = circle(30.0, 22.0, 15.0);
    field[5 * W + 5] = std::numeric_limits<float>::quiet_NaN();
    field[5 * W + 6] = std::numeric_limits<float>::infinity();
    const std::vector<float> outline = circle(30.0, 22.0, 15.0);
    const std::vector<float> other = circle(40.0, 26.0, 10.0);

    PreviewOptions options;
    options.lo = -20.0f;
    options.hi = 20.0f;
    options.colorMap = ColorMapKind::Diverging;
    options.contourFields = {outline.data(), other.data()};
    options.contourColors = {Rgb8{0, 0, 0}, Rgb8{0, 160, 0}};
    options.title = "d1 (source) [samples]";
    const Image8 image = renderFieldPreview(field.data(), W, H, options);

    // Enlarged by 6 (48 * 6 = 288 >= 256); margins and colour bar around it.
    const int s = 6;
    EXPECT_GE(image.width, W * s);
    EXPECT_GT(image.height, H * s + 40);
    ASSERT_EQ(image.rgb.size(), size_t(3) * image.width * image.height);

    std::set<int> colours;
    for (size_t i = 0; i < image.rgb.size(); i += 3) {
        colours.insert(image.rgb[i] << 16 | image.rgb[i + 1] << 8 | image.rgb[i + 2]);
    }
    EXPECT_GT(colours.size(), 50u);

    // Locate the field: the first row with a non-white pixel after the title is its frame.
    const int fieldX = (image.width - W * s) / 2;
    const int titleBottom = 12 + textHeight(2);
    int fieldY = -1;
    for (int y = titleBottom + 1; y < image.height && fieldY < 0; ++y) {
        if (image.at(image.width / 2, y) != Rgb8{255, 255, 255}) fieldY = y + 1; // skip frame
    }
    ASSERT_GT(fieldY, 0);
    auto fieldPixel = [&](double fx, double fy) {
        return image.at(fieldX + int((fx + 0.5) * s), fieldY + int((fy + 0.5) * s));
    };
    EXPECT_EQ(fieldPixel(5.0, 5.0), NAN_COLOR);
    EXPECT_EQ(fieldPixel(6.0, 5.0), NAN_COLOR);
    // Inside the circle the field is negative (blue side), outside positive (red side).
    const Rgb8 inside = fieldPixel(30.0, 22.0), outside = fieldPixel(60.0, 45.0);
    EXPECT_GT(inside[2], inside[0]);
    EXPECT_GT(outside[0], outside[2]);

    // The contour passes through (45, 22) (rightmost point of the circle): a black pixel near it.
    bool contourFound = false;
    const int cx = fieldX + int(45.5 * s), cy = fieldY + int(22.5 * s);
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx)
            contourFound |= image.at(cx + dx, cy + dy) == Rgb8{0, 0, 0};
    }
    EXPECT_TRUE(contourFound);
    // The green contour of the second circle passes through (50, 26).
    bool greenFound = false;
    const int gx = fieldX + int(50.5 * s), gy = fieldY + int(26.5 * s);
    for (int dy = -2; dy <= 2; ++dy) {
        for (int dx = -2; dx <= 2; ++dx)
            greenFound |= image.at(gx + dx, gy + dy) == Rgb8{0, 160, 0};
    }
    EXPECT_TRUE(greenFound);
    // No contour far from both circles, e.g. around sample (8, 40).
    EXPECT_NE(fieldPixel(8.0, 40.0), (Rgb8{0, 0, 0}));

    // Text: the title rows and the label rows below the colour bar hold dark pixels.
    EXPECT_GT(darkPixelsInRows(image, 12, 12 + textHeight(2)), 100);
    const int labelRows = textHeight(2) + 12;
    EXPECT_GT(darkPixelsInRows(image, image.height - labelRows, image.height), 60);

    const std::string samples = test::sampleDirectory();
    const std::string path = samples.empty()
                                 ? (std::filesystem::temp_directory_path() /
                                    ("vdbmatch-preview-" + std::to_string(::getpid()) + ".png"))
                                       .string()
                                 : samples + "/preview.png";
    writePng(path, image.width, image.height, image.rgb);
    EXPECT_TRUE(std::filesystem::exists(path));
    if (samples.empty()) std::filesystem::remove(path);
}

TEST(Preview, InfernoSample)
{
    // A field with a jump, as in the paper's fig:jump: x + a step.
    std::vector<float> field(W * H), a(W * H);
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            field[y * W + x] = float(x) / W + (y > H / 2 ? 0.5f : 0.0f);
            a[y * W + x] = float(std::hypot(x - 20.0, y - 20.0) - 12.0);
        }
    }
    PreviewOptions options;
    options.lo = 0.0f;
    options.hi = 1.5f;
    options.contourFields = {a.data()};
    options.title = "|D phi| 1.5e-3";
    const Image8 image = renderFieldPreview(field.data(), W, H, options);
    EXPECT_GT(darkPixelsInRows(image, image.height - 26, image.height), 30);
    const std::string samples = test::sampleDirectory();
    if (!samples.empty()) {
        writePng(samples + "/preview_inferno.png", image.width, image.height, image.rgb);
    }
}

TEST(Preview, Helpers)
{
    const float values[] = {3.0f, std::numeric_limits<float>::quiet_NaN(), -2.0f, 1.0f};
    EXPECT_EQ(finiteRange(values, 4), (std::pair<float, float>(-2.0f, 3.0f)));
    EXPECT_EQ(formatTickLabel(-0.0), "0");
    EXPECT_EQ(formatTickLabel(0.125), "0.125");
    EXPECT_EQ(formatTickLabel(-1.5e-5), "-1.5e-05");
    EXPECT_EQ(textWidth("ab", 2), 22);
}

TEST(Preview, RejectsBadInput)
{
    const float f[4] = {0, 1, 2, 3};
    PreviewOptions options;
    EXPECT_THROW(renderFieldPreview(nullptr, 2, 2, options), openvdb::ValueError);
    EXPECT_THROW(renderFieldPreview(f, 0, 2, options), openvdb::ValueError);
    options.lo = 2.0f;
    options.hi = 1.0f;
    EXPECT_THROW(renderFieldPreview(f, 2, 2, options), openvdb::ValueError);
    options = PreviewOptions();
    options.contourFields = {nullptr};
    EXPECT_THROW(renderFieldPreview(f, 2, 2, options), openvdb::ValueError);
}
