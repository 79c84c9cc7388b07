/// @file Curves2D.cc
/// @brief Thick coloured polylines and grid lines in the plane.
#include "Curves2D.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vdbmatch {

namespace {

constexpr int SUPERSAMPLE = 2;
constexpr Rgb8 BLACK = {0, 0, 0};

} // namespace

Image8
renderCurves2D(const std::vector<ColoredPolyline2D>& curves,
               const std::vector<std::vector<openvdb::Vec2d>>& gridLines,
               const openvdb::Vec2d& frameMin, const openvdb::Vec2d& frameMax, int width,
               int height, const Curves2DOptions& options)
{
    if (width <= 0 || height <= 0) {
        OPENVDB_THROW(openvdb::ValueError, "renderCurves2D: image size " + std::to_string(width) +
                                               " x " + std::to_string(height) + " is not positive");
    }
    const openvdb::Vec2d extent = frameMax - frameMin;
    if (!(extent.x() > 0.0 && extent.y() > 0.0) || !std::isfinite(extent.x()) ||
        !std::isfinite(extent.y())) {
        OPENVDB_THROW(
            openvdb::ValueError,
            "renderCurves2D: the frame is empty or not finite (need frameMin < frameMax)");
    }
    for (const auto& c : curves) {
        if (!c.colors.empty() && c.colors.size() != c.points.size()) {
            OPENVDB_THROW(openvdb::ValueError,
                          "renderCurves2D: a curve has " + std::to_string(c.colors.size()) +
                              " colours for " + std::to_string(c.points.size()) + " points");
        }
    }
    if (!(options.marginFraction >= 0.0 && options.marginFraction < 0.5)) {
        OPENVDB_THROW(openvdb::ValueError, "renderCurves2D: marginFraction " +
                                               std::to_string(options.marginFraction) +
                                               " is not in [0, 0.5)");
    }
    const int ss = options.supersample ? SUPERSAMPLE : 1;
    const int W = width * ss, H = height * ss;
    const double margin = options.marginFraction * std::min(W, H);
    const double scale = std::min((W - 2.0 * margin) / extent.x(), (H - 2.0 * margin) / extent.y());
    const openvdb::Vec2d centre = 0.5 * (frameMin + frameMax);
    auto toPixel = [&](const openvdb::Vec2d& p, double& x, double& y) {
        x = 0.5 * W + scale * (p.x() - centre.x());
        y = 0.5 * H - scale * (p.y() - centre.y());
    };

    Image8 image(W, H, options.background);
    for (const auto& line : gridLines) {
        for (size_t i = 0; i + 1 < line.size(); ++i) {
            double ax, ay, bx, by;
            toPixel(line[i], ax, ay);
            toPixel(line[i + 1], bx, by);
            drawSegment(image, ax, ay, bx, by, options.gridWidthPx * ss, options.gridColor,
                        options.gridColor);
        }
    }
    for (const auto& curve : curves) {
        const size_t n = curve.points.size();
        const size_t segments = curve.closed && n > 2 ? n : (n > 0 ? n - 1 : 0);
        const double widthPx = curve.widthPx > 0.0 ? curve.widthPx : options.curveWidthPx;
        for (size_t i = 0; i < segments; ++i) {
            const size_t j = (i + 1) % n;
            double ax, ay, bx, by;
            toPixel(curve.points[i], ax, ay);
            toPixel(curve.points[j], bx, by);
            const Rgb8 ca = curve.colors.empty() ? BLACK : curve.colors[i];
            const Rgb8 cb = curve.colors.empty() ? BLACK : curve.colors[j];
            drawSegment(image, ax, ay, bx, by, widthPx * ss, ca, cb);
        }
    }
    return ss == 1 ? image : downsample2x(image);
}

} // namespace vdbmatch
