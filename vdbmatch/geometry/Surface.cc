/// @file Surface.cc
/// @brief Bounding box, placement and validity checks of explicit surfaces and curves.
#include "Surface.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {

namespace {

openvdb::Vec3d
toVec3d(const Vec<2>& p)
{
    return openvdb::Vec3d(p[0], p[1], 0.0);
}
openvdb::Vec3d
toVec3d(const Vec<3>& p)
{
    return openvdb::Vec3d(p[0], p[1], p[2]);
}

template <int D>
Vec<D>
fromVec3d(const openvdb::Vec3d& p)
{
    Vec<D> v;
    for (int a = 0; a < D; ++a)
        v[a] = p[a];
    return v;
}

[[noreturn]] void
fail(const std::string& what, const std::string& problem)
{
    OPENVDB_THROW(openvdb::ValueError, "checkSurface: " + what + ": " + problem);
}

/// Every undirected edge of the triangles must be shared by exactly two of them.
void
checkClosed(const Surface<3>& s, const std::string& what)
{
    std::vector<uint64_t> edges;
    edges.reserve(s.elements.size() * 3);
    for (const auto& t : s.elements) {
        for (int c = 0; c < 3; ++c) {
            const uint32_t a = uint32_t(t[size_t(c)]), b = uint32_t(t[size_t((c + 1) % 3)]);
            edges.push_back((uint64_t(std::min(a, b)) << 32) | uint64_t(std::max(a, b)));
        }
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j] == edges[i])
            ++j;
        if (j - i != 2) {
            std::ostringstream m;
            m << "the surface is not closed: edge (" << (edges[i] >> 32) << ", "
              << (edges[i] & 0xffffffffu) << ") is shared by " << (j - i)
              << " triangle(s), expected 2";
            fail(what, m.str());
        }
        i = j;
    }
}

/// Every vertex must be used by exactly two segments.
void
checkClosed(const Surface<2>& s, const std::string& what)
{
    std::vector<int> uses(s.points.size(), 0);
    for (const auto& e : s.elements) {
        ++uses[size_t(e[0])];
        ++uses[size_t(e[1])];
    }
    for (size_t v = 0; v < uses.size(); ++v) {
        if (uses[v] != 2) {
            std::ostringstream m;
            m << "the curve is not closed: vertex " << v << " is used by " << uses[v]
              << " segment(s), expected 2";
            fail(what, m.str());
        }
    }
}

} // namespace

template <int D>
openvdb::BBoxd
boundingBox(const Surface<D>& surface)
{
    openvdb::BBoxd box;
    bool first = true;
    for (const Vec<D>& p : surface.points) {
        const openvdb::Vec3d q = toVec3d(p);
        if (first) box = openvdb::BBoxd(q, q);
        box.expand(q);
        first = false;
    }
    return box;
}

template <int D>
Surface<D>
transformed(const Surface<D>& surface, const UnitBoxPlacement& placement,
            PlacementDirection direction)
{
    Surface<D> out;
    out.elements = surface.elements;
    out.points.reserve(surface.points.size());
    const bool toUnit = direction == PlacementDirection::WorldToUnit;
    for (const Vec<D>& p : surface.points) {
        const openvdb::Vec3d q = toVec3d(p);
        Vec<D> r = fromVec3d<D>(toUnit ? placement.toUnit(q) : placement.toWorld(q));
        out.points.push_back(r);
    }
    return out;
}

template <int D>
void
checkSurface(const Surface<D>& surface, const std::string& what)
{
    const char* elementName = D == 3 ? "triangle" : "segment";
    if (surface.points.empty() || surface.elements.empty()) {
        fail(what, std::string("empty: no ") + elementName + "s");
    }
    for (size_t v = 0; v < surface.points.size(); ++v) {
        if (!surface.points[v].allFinite()) {
            std::ostringstream m;
            m << "vertex " << v << " has a non-finite coordinate (NaN or infinity)";
            fail(what, m.str());
        }
    }
    const int64_t n = int64_t(surface.points.size());
    for (size_t e = 0; e < surface.elements.size(); ++e) {
        const auto& el = surface.elements[e];
        for (int c = 0; c < D; ++c) {
            const int64_t i = el[size_t(c)];
            if (i < 0 || i >= n) {
                std::ostringstream m;
                m << elementName << " " << e << " refers to vertex " << i << ", but there are " << n
                  << " vertices";
                fail(what, m.str());
            }
            for (int c2 = 0; c2 < c; ++c2) {
                if (el[size_t(c2)] == el[size_t(c)]) {
                    std::ostringstream m;
                    m << elementName << " " << e << " repeats vertex " << i;
                    fail(what, m.str());
                }
            }
        }
    }
    checkClosed(surface, what);
    const openvdb::Vec3d extents = boundingBox(surface).extents();
    int flat = 0;
    for (int a = 0; a < D; ++a)
        flat += extents[a] > 0.0 ? 0 : 1;
    if (flat > 0) {
        std::ostringstream m;
        m << "degenerate: the bounding box has zero extent along " << flat << " axis/axes";
        fail(what, m.str());
    }
}

template <>
double
measure<2>(const Surface<2>& s)
{
    double sum = 0.0;
    for (const auto& e : s.elements)
        sum += (s.points[size_t(e[1])] - s.points[size_t(e[0])]).norm();
    return sum;
}

template <>
double
measure<3>(const Surface<3>& s)
{
    double sum = 0.0;
    for (const auto& t : s.elements) {
        const Vec<3>& a = s.points[size_t(t[0])];
        sum += 0.5 * (s.points[size_t(t[1])] - a).cross(s.points[size_t(t[2])] - a).norm();
    }
    return sum;
}

template <>
double
signedVolume<2>(const Surface<2>& s)
{
    double sum = 0.0;
    for (const auto& e : s.elements) {
        const Vec<2>& a = s.points[size_t(e[0])];
        const Vec<2>& b = s.points[size_t(e[1])];
        sum += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * sum;
}

template <>
double
signedVolume<3>(const Surface<3>& s)
{
    double sum = 0.0;
    for (const auto& t : s.elements) {
        sum += s.points[size_t(t[0])].dot(s.points[size_t(t[1])].cross(s.points[size_t(t[2])]));
    }
    return sum / 6.0;
}

template struct Surface<2>;
template struct Surface<3>;
template openvdb::BBoxd boundingBox<2>(const Surface<2>&);
template openvdb::BBoxd boundingBox<3>(const Surface<3>&);
template Surface<2> transformed<2>(const Surface<2>&, const UnitBoxPlacement&, PlacementDirection);
template Surface<3> transformed<3>(const Surface<3>&, const UnitBoxPlacement&, PlacementDirection);
template void checkSurface<2>(const Surface<2>&, const std::string&);
template void checkSurface<3>(const Surface<3>&, const std::string&);

} // namespace vdbmatch
