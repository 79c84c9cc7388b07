/// @file MatrixPlots.cc
#include "MatrixPlots.h"

#include <vdbmatch/render/BitmapFont.h>
#include <vdbmatch/render/ColorMap.h>
#include <vdbmatch/render/Preview.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>

namespace vdbmatch {
namespace render {

namespace {

constexpr Rgb8 WHITE{255, 255, 255};
constexpr Rgb8 BLACK{0, 0, 0};
constexpr Rgb8 GREY{160, 160, 160};
constexpr int MARGIN = 12;

} // namespace

Image8
distanceHeatMap(const eval::DistanceMatrix& m, const std::vector<std::string>& names,
                const std::vector<int>& order, const std::string& title)
{
    const int n = m.n;
    if (int(names.size()) != n || int(order.size()) != n)
        OPENVDB_THROW(openvdb::ValueError, "distanceHeatMap: " << names.size() << " names and "
                                                               << order.size() << " indices for "
                                                               << n << " shapes");
    std::vector<int> seen(std::size_t(n), 0);
    for (int k : order) {
        if (k < 0 || k >= n || seen[std::size_t(k)]++)
            OPENVDB_THROW(openvdb::ValueError, "distanceHeatMap: order is not a permutation");
    }
    double hi = 0;
    for (double v : m.d)
        if (std::isfinite(v)) hi = std::max(hi, v);
    const int cell = std::clamp(640 / std::max(1, n), 3, 40);
    const int scale = 1;
    int labelWidth = 0;
    for (int k = 0; k < n; ++k)
        labelWidth = std::max(labelWidth, textWidth(std::to_string(k + 1) + " " +
                                                        names[std::size_t(order[std::size_t(k)])],
                                                    scale));
    const bool labelRows = cell >= textHeight(scale);
    const int left = MARGIN + (labelRows ? labelWidth + 6 : 0);
    const int top = MARGIN + 2 * textHeight(2) + (labelRows ? textHeight(scale) + 4 : 0);
    const int barWidth = 16, barGap = 16;
    const int side = n * cell;
    const int width =
        std::max(left + side + barGap + barWidth + 8 + textWidth("0.000e+00", scale) + MARGIN,
                 textWidth(title, 2) + 2 * MARGIN);
    const int height = top + std::max(side, 80) + MARGIN;
    Image8 image(width, height, WHITE);
    drawText(image, MARGIN, MARGIN, title, BLACK, 2);
    for (int r = 0; r < n; ++r) {
        for (int c = 0; c < n; ++c) {
            const double v = m.at(order[std::size_t(r)], order[std::size_t(c)]);
            const Rgb8 colour = std::isfinite(v)
                                    ? mapValue(v, 0.0, hi > 0 ? hi : 1.0, ColorMapKind::Inferno)
                                    : GREY;
            fillRect(image, left + c * cell, top + r * cell, left + (c + 1) * cell,
                     top + (r + 1) * cell, colour);
        }
        if (labelRows) {
            const std::string label =
                std::to_string(r + 1) + " " + names[std::size_t(order[std::size_t(r)])];
            drawText(image, left - 6 - textWidth(label, scale),
                     top + r * cell + (cell - textHeight(scale)) / 2, label, BLACK, scale);
            const std::string number = std::to_string(r + 1);
            if (textWidth(number, scale) <= cell + 2) {
                drawText(image, left + r * cell + (cell - textWidth(number, scale)) / 2,
                         top - textHeight(scale) - 4, number, BLACK, scale);
            }
        }
    }
    strokeRect(image, left - 1, top - 1, left + side + 1, top + side + 1, BLACK);
    // Colour bar: the largest entry at the top, 0 at the bottom.
    const int bx = left + side + barGap, barHeight = std::max(side, 80);
    for (int y = 0; y < barHeight; ++y) {
        const double t = 1.0 - (y + 0.5) / barHeight;
        fillRect(image, bx, top + y, bx + barWidth, top + y + 1,
                 colorMapAt(t, ColorMapKind::Inferno));
    }
    strokeRect(image, bx - 1, top - 1, bx + barWidth + 1, top + barHeight + 1, BLACK);
    drawText(image, bx + barWidth + 6, top, formatTickLabel(hi), BLACK, scale);
    drawText(image, bx + barWidth + 6, top + barHeight - textHeight(scale), "0", BLACK, scale);
    return image;
}

Image8
labelledScatter(const std::vector<Vec<2>>& points, const std::vector<std::string>& names,
                const std::string& title)
{
    if (points.size() != names.size())
        OPENVDB_THROW(openvdb::ValueError, "labelledScatter: " << points.size() << " points and "
                                                               << names.size() << " names");
    const int plot = 560, scale = 1;
    const int top = MARGIN + 2 * textHeight(2);
    Image8 image(std::max(plot + 2 * MARGIN + 120, textWidth(title, 2) + 2 * MARGIN),
                 top + plot + MARGIN, WHITE);
    drawText(image, MARGIN, MARGIN, title, BLACK, 2);
    double lo[2] = {0, 0}, hi[2] = {0, 0};
    for (std::size_t i = 0; i < points.size(); ++i)
        for (int a = 0; a < 2; ++a) {
            lo[a] = i ? std::min(lo[a], points[i][a]) : points[i][a];
            hi[a] = i ? std::max(hi[a], points[i][a]) : points[i][a];
        }
    // Equal scales on both axes, 8% padding.
    double span = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    if (!(span > 0)) span = 1;
    const double pad = 0.08 * span, s = plot / (span + 2 * pad);
    const double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
    strokeRect(image, MARGIN, top, MARGIN + plot, top + plot, BLACK);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double x = MARGIN + plot / 2.0 + (points[i][0] - cx) * s;
        const double y = top + plot / 2.0 - (points[i][1] - cy) * s;
        const Rgb8 colour =
            colorMapAt(points.size() > 1 ? double(i) / double(points.size() - 1) * 0.8 + 0.1 : 0.5,
                       ColorMapKind::Inferno);
        drawSegment(image, x, y, x, y, 8.0, colour, colour);
        drawText(image, int(x) + 6, int(y) - textHeight(scale) / 2, names[i], BLACK, scale);
    }
    return image;
}

} // namespace render
} // namespace vdbmatch
