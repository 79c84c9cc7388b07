/// @file Preview.cc
/// @brief Field preview: colour-mapped field, zero contours by marching squares, colour bar.
#include "Preview.h"

#include <vdbmatch/render/BitmapFont.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace vdbmatch {

namespace {

constexpr int MARGIN_PX = 12;     ///< white border around everything
constexpr int TEXT_SCALE = 2;     ///< font pixels are 2 x 2 image pixels
constexpr int GAP_PX = 10;        ///< between title, field, colour bar
constexpr int BAR_HEIGHT_PX = 18; ///< colour bar height
constexpr int TICK_LENGTH_PX = 6; ///< tick marks below the bar
constexpr int LABEL_GAP_PX = 4;   ///< between tick and label
constexpr double CONTOUR_WIDTH_PX = 1.0;
constexpr double HALO_WIDTH_PX = 3.0;
constexpr Rgb8 WHITE = {255, 255, 255};
constexpr Rgb8 BLACK = {0, 0, 0};
constexpr Rgb8 TEXT_COLOR = {20, 20, 20};
constexpr Rgb8 FRAME_COLOR = {60, 60, 60};

struct Segment
{
    double ax, ay, bx, by;
};

/// Zero-contour segments of @a f (w x h) in field-sample coordinates (sample centres at integer
/// positions).
std::vector<Segment>
marchingSquares(const float* f, int w, int h)
{
    std::vector<Segment> segments;
    auto value = [&](int x, int y) {
        return static_cast<double>(f[static_cast<size_t>(y) * w + x]);
    };
    for (int y = 0; y + 1 < h; ++y) {
        for (int x = 0; x + 1 < w; ++x) {
            // Corners counter-clockwise in the image: 0 (x, y), 1 (x+1, y), 2 (x+1, y+1),
            // 3 (x, y+1); edge k joins corner k and corner k+1.
            const std::array<double, 4> v = {value(x, y), value(x + 1, y), value(x + 1, y + 1),
                                             value(x, y + 1)};
            const std::array<double, 4> cx = {0, 1, 1, 0}, cy = {0, 0, 1, 1};
            if (!std::all_of(v.begin(), v.end(), [](double d) { return std::isfinite(d); })) {
                continue;
            }
            std::array<bool, 4> inside;
            for (int k = 0; k < 4; ++k)
                inside[k] = v[k] < 0.0;
            std::array<double, 4> px{}, py{};
            std::array<bool, 4> crossed{};
            int count = 0;
            for (int k = 0; k < 4; ++k) {
                const int l = (k + 1) % 4;
                if (inside[k] == inside[l]) continue;
                const double t = v[k] / (v[k] - v[l]);
                px[k] = x + cx[k] + t * (cx[l] - cx[k]);
                py[k] = y + cy[k] + t * (cy[l] - cy[k]);
                crossed[k] = true;
                ++count;
            }
            if (count == 2) {
                int a = -1, b = -1;
                for (int k = 0; k < 4; ++k) {
                    if (!crossed[k]) continue;
                    (a < 0 ? a : b) = k;
                }
                segments.push_back({px[a], py[a], px[b], py[b]});
            } else if (count == 4) {
                const bool centreInside = (v[0] + v[1] + v[2] + v[3]) < 0.0;
                if (centreInside == inside[0]) {
                    // Corner 0 joins the centre: corners 1 and 3 are cut off.
                    segments.push_back({px[0], py[0], px[1], py[1]});
                    segments.push_back({px[2], py[2], px[3], py[3]});
                } else {
                    segments.push_back({px[3], py[3], px[0], py[0]});
                    segments.push_back({px[1], py[1], px[2], py[2]});
                }
            }
        }
    }
    return segments;
}

} // namespace

std::pair<float, float>
finiteRange(const float* values, size_t count)
{
    bool any = false;
    float lo = 0.0f, hi = 0.0f;
    for (size_t i = 0; i < count; ++i) {
        const float v = values[i];
        if (!std::isfinite(v)) continue;
        if (!any) {
            lo = hi = v;
            any = true;
        }
        lo = std::min(lo, v);
        hi = std::max(hi, v);
    }
    return {lo, hi};
}

std::string
formatTickLabel(double value)
{
    if (value == 0.0) return "0";
    char buffer[32];
    std::snprintf(buffer, sizeof(buffer), "%.3g", value);
    return buffer;
}

Image8
renderFieldPreview(const float* field, int width, int height, const PreviewOptions& options)
{
    if (!field) OPENVDB_THROW(openvdb::ValueError, "renderFieldPreview: the field is null");
    if (width <= 0 || height <= 0) {
        OPENVDB_THROW(openvdb::ValueError, "renderFieldPreview: field size " +
                                               std::to_string(width) + " x " +
                                               std::to_string(height) + " is not positive");
    }
    if (!std::isfinite(options.lo) || !std::isfinite(options.hi) || options.lo > options.hi) {
        OPENVDB_THROW(openvdb::ValueError,
                      "renderFieldPreview: the range [lo, hi] = [" + std::to_string(options.lo) +
                          ", " + std::to_string(options.hi) + "] is not finite with lo <= hi");
    }
    for (const float* c : options.contourFields) {
        if (!c) OPENVDB_THROW(openvdb::ValueError, "renderFieldPreview: a contour field is null");
    }

    const int shortSide = std::min(width, height);
    const int s = std::max(1, (std::max(options.minShortSidePx, 1) + shortSide - 1) / shortSide);
    const int fieldW = width * s, fieldH = height * s;

    const std::string loLabel = formatTickLabel(options.lo);
    const std::string midLabel = formatTickLabel(0.5 * (double(options.lo) + options.hi));
    const std::string hiLabel = formatTickLabel(options.hi);
    const int titleH = options.title.empty() ? 0 : textHeight(TEXT_SCALE) + GAP_PX;
    // Wide enough for the title and for the three labels side by side without overlap.
    const int labelsW =
        2 * std::max(textWidth(loLabel, TEXT_SCALE), textWidth(hiLabel, TEXT_SCALE)) +
        textWidth(midLabel, TEXT_SCALE) + 2 * GAP_PX;
    const int contentW = std::max({fieldW, textWidth(options.title, TEXT_SCALE), labelsW});
    const int imageW = contentW + 2 * MARGIN_PX;
    const int fieldX = MARGIN_PX + (contentW - fieldW) / 2;
    const int fieldY = MARGIN_PX + titleH;
    const int barY = fieldY + fieldH + GAP_PX;
    const int labelY = barY + BAR_HEIGHT_PX + TICK_LENGTH_PX + LABEL_GAP_PX;
    const int imageH = labelY + textHeight(TEXT_SCALE) + MARGIN_PX;

    Image8 image(imageW, imageH, WHITE);
    if (!options.title.empty()) {
        drawText(image, MARGIN_PX + (contentW - textWidth(options.title, TEXT_SCALE)) / 2,
                 MARGIN_PX, options.title, TEXT_COLOR, TEXT_SCALE);
    }

    // The field, enlarged.
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const Rgb8 c = mapValue(field[static_cast<size_t>(y) * width + x], options.lo,
                                    options.hi, options.colorMap);
            fillRect(image, fieldX + x * s, fieldY + y * s, fieldX + (x + 1) * s,
                     fieldY + (y + 1) * s, c);
        }
    }

    // Zero contours: all halos first, then the lines, so that no halo hides a line.
    std::vector<std::vector<Segment>> contours;
    for (const float* c : options.contourFields)
        contours.push_back(marchingSquares(c, width, height));
    auto toImageX = [&](double sx) { return fieldX + (sx + 0.5) * s; };
    auto toImageY = [&](double sy) { return fieldY + (sy + 0.5) * s; };
    for (const auto& segments : contours) {
        for (const Segment& g : segments) {
            drawSegment(image, toImageX(g.ax), toImageY(g.ay), toImageX(g.bx), toImageY(g.by),
                        HALO_WIDTH_PX, WHITE, WHITE);
        }
    }
    for (size_t k = 0; k < contours.size(); ++k) {
        const Rgb8 color = k < options.contourColors.size() ? options.contourColors[k] : BLACK;
        for (const Segment& g : contours[k]) {
            drawSegment(image, toImageX(g.ax), toImageY(g.ay), toImageX(g.bx), toImageY(g.by),
                        CONTOUR_WIDTH_PX, color, color);
        }
    }
    strokeRect(image, fieldX - 1, fieldY - 1, fieldX + fieldW + 1, fieldY + fieldH + 1,
               FRAME_COLOR);

    // Colour bar, as wide as the content, with ticks and labels at lo, mid, hi.
    const int barX = MARGIN_PX;
    for (int x = 0; x < contentW; ++x) {
        const double t = contentW > 1 ? double(x) / (contentW - 1) : 0.5;
        fillRect(image, barX + x, barY, barX + x + 1, barY + BAR_HEIGHT_PX,
                 colorMapAt(t, options.colorMap));
    }
    strokeRect(image, barX - 1, barY - 1, barX + contentW + 1, barY + BAR_HEIGHT_PX + 1,
               FRAME_COLOR);
    const std::array<int, 3> tickX = {barX, barX + (contentW - 1) / 2, barX + contentW - 1};
    const std::array<std::string, 3> labels = {loLabel, midLabel, hiLabel};
    for (int k = 0; k < 3; ++k) {
        fillRect(image, tickX[k], barY + BAR_HEIGHT_PX, tickX[k] + 1,
                 barY + BAR_HEIGHT_PX + TICK_LENGTH_PX, TEXT_COLOR);
        const int w = textWidth(labels[k], TEXT_SCALE);
        // The first label starts at its tick, the last ends at its tick, the middle is centred.
        int x = k == 0 ? tickX[k] : (k == 2 ? tickX[k] + 1 - w : tickX[k] - w / 2);
        x = std::clamp(x, 0, std::max(0, imageW - w));
        drawText(image, x, labelY, labels[k], TEXT_COLOR, TEXT_SCALE);
    }
    return image;
}

} // namespace vdbmatch
