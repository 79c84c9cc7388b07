/// @file Texture.cc
/// @brief Stripe, checker and position colour patterns on surfaces and curves.
#include "Texture.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace vdbmatch {

namespace {

constexpr double PI = 3.14159265358979323846;
/// Grey for points with a non-finite coordinate.
constexpr Rgb8 NON_FINITE_COLOR = {128, 128, 128};

/// Band index of @a t in [0, 1) cut into @a cells equal bands; t = 1 falls into the last band.
long
band(double t, int cells)
{
    return std::clamp(static_cast<long>(std::floor(t * cells)), 0L, static_cast<long>(cells) - 1);
}

inline const Rgb8&
pick(long index, const Rgb8& a, const Rgb8& b)
{
    return (index % 2 == 0) ? a : b;
}

/// Colour A or B by the parity of floor(@a x), for any finite x (no integer overflow).
const Rgb8&
pickByFloor(double x, const Rgb8& a, const Rgb8& b)
{
    return std::abs(std::fmod(std::floor(x), 2.0)) < 0.5 ? a : b;
}

std::uint8_t
normalized(double v, double lo, double hi)
{
    const double t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
    return static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(t, 0.0, 1.0)));
}

} // namespace

std::vector<Rgb8>
paintSurface(const std::vector<openvdb::Vec3d>& points, const SurfaceTexture& texture)
{
    if (texture.axis < 0 || texture.axis > 2) {
        OPENVDB_THROW(openvdb::ValueError,
                      "paintSurface: axis " + std::to_string(texture.axis) + " is not 0, 1 or 2");
    }
    if (!(texture.stripeWidth > 0.0)) {
        OPENVDB_THROW(openvdb::ValueError, "paintSurface: stripeWidth must be positive");
    }
    if (texture.longitudeCells < 1 || texture.latitudeCells < 1) {
        OPENVDB_THROW(openvdb::ValueError, "paintSurface: cell counts must be at least 1");
    }
    std::vector<Rgb8> colors(points.size());
    if (points.empty()) return colors;

    // Bounding box and centroid of the finite points.
    openvdb::Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    openvdb::Vec3d sum(0.0);
    size_t finiteCount = 0;
    for (const auto& p : points) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) continue;
        lo = openvdb::math::minComponent(lo, p);
        hi = openvdb::math::maxComponent(hi, p);
        sum += p;
        ++finiteCount;
    }
    const openvdb::Vec3d centre =
        texture.center ? *texture.center : sum / double(std::max<size_t>(finiteCount, 1));
    const int a = texture.axis, u = (a + 1) % 3, v = (a + 2) % 3;

    for (size_t i = 0; i < points.size(); ++i) {
        const openvdb::Vec3d& p = points[i];
        const openvdb::Vec3d d = p - centre;
        if (!std::isfinite(d.x()) || !std::isfinite(d.y()) || !std::isfinite(d.z())) {
            colors[i] = NON_FINITE_COLOR;
            continue;
        }
        // Longitude in [0, 1) of a turn; latitude in [0, 1] from the -axis pole to the +axis pole.
        const double longitude = (std::atan2(d[v], d[u]) + PI) / (2.0 * PI);
        const double latitude = (std::atan2(d[a], std::hypot(d[u], d[v])) + 0.5 * PI) / PI;
        switch (texture.pattern) {
        case SurfacePattern::AxisStripes: {
            colors[i] =
                pickByFloor((p[a] - lo[a]) / texture.stripeWidth, texture.colorA, texture.colorB);
            break;
        }
        case SurfacePattern::LongitudeStripes:
            colors[i] =
                pick(band(longitude, texture.longitudeCells), texture.colorA, texture.colorB);
            break;
        case SurfacePattern::Checker:
            colors[i] = pick(band(longitude, texture.longitudeCells) +
                                 band(latitude, texture.latitudeCells),
                             texture.colorA, texture.colorB);
            break;
        case SurfacePattern::Position:
            colors[i] = {normalized(p.x(), lo.x(), hi.x()), normalized(p.y(), lo.y(), hi.y()),
                         normalized(p.z(), lo.z(), hi.z())};
            break;
        }
    }
    return colors;
}

std::vector<Rgb8>
paintCurve(const std::vector<openvdb::Vec2d>& points, const CurveTexture& texture)
{
    if (!(texture.stripeWidth > 0.0)) {
        OPENVDB_THROW(openvdb::ValueError, "paintCurve: stripeWidth must be positive");
    }
    if (texture.angleCells < 1) {
        OPENVDB_THROW(openvdb::ValueError, "paintCurve: angleCells must be at least 1");
    }
    std::vector<Rgb8> colors(points.size());
    if (points.empty()) return colors;

    // Bounding box and centroid of the finite points.
    openvdb::Vec2d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    openvdb::Vec2d sum(0.0);
    size_t finiteCount = 0;
    for (const auto& p : points) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;
        lo = openvdb::Vec2d(std::min(lo.x(), p.x()), std::min(lo.y(), p.y()));
        hi = openvdb::Vec2d(std::max(hi.x(), p.x()), std::max(hi.y(), p.y()));
        sum += p;
        ++finiteCount;
    }
    const openvdb::Vec2d centre =
        texture.center ? *texture.center : sum / double(std::max<size_t>(finiteCount, 1));

    double arcLength = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
        const openvdb::Vec2d& p = points[i];
        if (!std::isfinite(p.x()) || !std::isfinite(p.y())) {
            colors[i] = NON_FINITE_COLOR;
            continue;
        }
        if (i > 0 && std::isfinite(points[i - 1].x()) && std::isfinite(points[i - 1].y())) {
            arcLength += (p - points[i - 1]).length();
        }
        switch (texture.pattern) {
        case CurvePattern::ArcLengthStripes:
            colors[i] =
                pickByFloor(arcLength / texture.stripeWidth, texture.colorA, texture.colorB);
            break;
        case CurvePattern::AngleStripes: {
            const double angle =
                (std::atan2(p.y() - centre.y(), p.x() - centre.x()) + PI) / (2.0 * PI);
            colors[i] = pick(band(angle, texture.angleCells), texture.colorA, texture.colorB);
            break;
        }
        case CurvePattern::Position: {
            const std::uint8_t r = normalized(p.x(), lo.x(), hi.x());
            colors[i] = {r, normalized(p.y(), lo.y(), hi.y()), static_cast<std::uint8_t>(255 - r)};
            break;
        }
        }
    }
    return colors;
}

} // namespace vdbmatch
