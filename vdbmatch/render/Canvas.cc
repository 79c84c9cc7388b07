/// @file Canvas.cc
/// @brief Image8 and its drawing primitives.
#include "Canvas.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vdbmatch {

namespace {

/// Half the width of the thinnest line drawn: pixels within half a pixel of the segment.
constexpr double MIN_HALF_WIDTH_PX = 0.5;

} // namespace

Image8::Image8(int w, int h, const Rgb8& fill) : width(w), height(h)
{
    if (w < 0 || h < 0) {
        OPENVDB_THROW(openvdb::ValueError,
                      "Image8: negative size " + std::to_string(w) + " x " + std::to_string(h));
    }
    rgb.resize(3 * static_cast<size_t>(w) * static_cast<size_t>(h));
    for (size_t i = 0; i < rgb.size(); i += 3) {
        rgb[i] = fill[0];
        rgb[i + 1] = fill[1];
        rgb[i + 2] = fill[2];
    }
}

Rgb8
Image8::at(int x, int y) const
{
    const size_t i = 3 * (static_cast<size_t>(y) * width + x);
    return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void
Image8::set(int x, int y, const Rgb8& c)
{
    if (!contains(x, y)) return;
    const size_t i = 3 * (static_cast<size_t>(y) * width + x);
    rgb[i] = c[0];
    rgb[i + 1] = c[1];
    rgb[i + 2] = c[2];
}

void
fillRect(Image8& image, int x0, int y0, int x1, int y1, const Rgb8& c)
{
    x0 = std::max(x0, 0);
    y0 = std::max(y0, 0);
    x1 = std::min(x1, image.width);
    y1 = std::min(y1, image.height);
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x)
            image.set(x, y, c);
    }
}

void
strokeRect(Image8& image, int x0, int y0, int x1, int y1, const Rgb8& c)
{
    if (x1 <= x0 || y1 <= y0) return;
    fillRect(image, x0, y0, x1, y0 + 1, c);
    fillRect(image, x0, y1 - 1, x1, y1, c);
    fillRect(image, x0, y0, x0 + 1, y1, c);
    fillRect(image, x1 - 1, y0, x1, y1, c);
}

void
drawSegment(Image8& image, double ax, double ay, double bx, double by, double widthPx,
            const Rgb8& ca, const Rgb8& cb)
{
    if (!std::isfinite(ax) || !std::isfinite(ay) || !std::isfinite(bx) || !std::isfinite(by)) {
        return;
    }
    const double r = std::max(0.5 * widthPx, MIN_HALF_WIDTH_PX);
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min(ax, bx) - r)));
    const int x1 = std::min(image.width - 1, static_cast<int>(std::ceil(std::max(ax, bx) + r)));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min(ay, by) - r)));
    const int y1 = std::min(image.height - 1, static_cast<int>(std::ceil(std::max(ay, by) + r)));
    const double dx = bx - ax, dy = by - ay;
    const double len2 = dx * dx + dy * dy;
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            const double px = x + 0.5 - ax, py = y + 0.5 - ay;
            const double t = len2 > 0.0 ? std::clamp((px * dx + py * dy) / len2, 0.0, 1.0) : 0.0;
            const double ex = px - t * dx, ey = py - t * dy;
            if (ex * ex + ey * ey > r * r) continue;
            Rgb8 c;
            for (int k = 0; k < 3; ++k) {
                c[k] = static_cast<std::uint8_t>(std::lround((1.0 - t) * ca[k] + t * cb[k]));
            }
            image.set(x, y, c);
        }
    }
}

Image8
downsample2x(const Image8& image)
{
    Image8 out(image.width / 2, image.height / 2, Rgb8{0, 0, 0});
    for (int y = 0; y < out.height; ++y) {
        for (int x = 0; x < out.width; ++x) {
            Rgb8 c;
            for (int k = 0; k < 3; ++k) {
                const int sum = image.at(2 * x, 2 * y)[k] + image.at(2 * x + 1, 2 * y)[k] +
                                image.at(2 * x, 2 * y + 1)[k] + image.at(2 * x + 1, 2 * y + 1)[k];
                c[k] = static_cast<std::uint8_t>((sum + 2) / 4);
            }
            out.set(x, y, c);
        }
    }
    return out;
}

void
paste(Image8& dst, const Image8& src, int x, int y)
{
    for (int j = 0; j < src.height; ++j) {
        for (int i = 0; i < src.width; ++i)
            dst.set(x + i, y + j, src.at(i, j));
    }
}

} // namespace vdbmatch
