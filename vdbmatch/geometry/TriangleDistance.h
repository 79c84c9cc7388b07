/// @file TriangleDistance.h
/// @brief Exact squared distances from a point to a triangle and to a segment (shared by the
///        distance builders and the target residual of match()).
#pragma once

#include <vdbmatch/Types.h>

#include <openvdb/openvdb.h>

#include <algorithm>
#include <limits>

namespace vdbmatch {
namespace detail {

/// Squared distance from p to the segment (a, b); a degenerate segment is the point a.
inline double
segmentDistanceSqr(const Vec<2>& p, const Vec<2>& a, const Vec<2>& b)
{
    const Vec<2> ab = b - a, ap = p - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0.0 ? std::clamp(ap.dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (ap - t * ab).squaredNorm();
}

/// Squared distance from p to the triangle (a, b, c), by the Voronoi regions of its corners and
/// edges (Ericson, Real-Time Collision Detection, 5.1.5). Degenerate triangles fall back to
/// their edges.
inline double
triangleDistanceSqr(const openvdb::Vec3d& p, const openvdb::Vec3d& a, const openvdb::Vec3d& b,
                    const openvdb::Vec3d& c)
{
    using openvdb::Vec3d;
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0.0 && d2 <= 0.0) return ap.lengthSqr();
    const Vec3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0.0 && d4 <= d3) return bp.lengthSqr();
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 && d1 - d3 > 0.0) {
        return (ap - ab * (d1 / (d1 - d3))).lengthSqr();
    }
    const Vec3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0.0 && d5 <= d6) return cp.lengthSqr();
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 && d2 - d6 > 0.0) {
        return (ap - ac * (d2 / (d2 - d6))).lengthSqr();
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 && (d4 - d3) + (d5 - d6) > 0.0) {
        return (bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))).lengthSqr();
    }
    const double area = va + vb + vc;
    if (area > 0.0) return (ap - ab * (vb / area) - ac * (vc / area)).lengthSqr();
    // Degenerate (collinear or coincident corners): the nearest of the three edges.
    double best = std::numeric_limits<double>::max();
    const Vec3d corner[3] = {a, b, c};
    for (int e = 0; e < 3; ++e) {
        const Vec3d& s = corner[e];
        const Vec3d d = corner[(e + 1) % 3] - s;
        const double len2 = d.lengthSqr();
        const double t = len2 > 0.0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
        best = std::min(best, (p - s - d * t).lengthSqr());
    }
    return best;
}

} // namespace detail
} // namespace vdbmatch
