/// @file SurfacePieces.cc
/// @brief Connected pieces of a surface by union-find over the elements' vertices.
#include "SurfacePieces.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace vdbmatch {

namespace {

double
elementMeasure(const Surface<3>& s, const std::array<int32_t, 3>& e)
{
    return 0.5 * (s.points[e[1]] - s.points[e[0]]).cross(s.points[e[2]] - s.points[e[0]]).norm();
}
double
elementMeasure(const Surface<2>& s, const std::array<int32_t, 2>& e)
{
    return (s.points[e[1]] - s.points[e[0]]).norm();
}

std::size_t
findRoot(std::vector<std::size_t>& parent, std::size_t i)
{
    while (parent[i] != i) {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    return i;
}

/// Euclidean gap between two boxes, 0 where they overlap.
double
boxGap(const openvdb::BBoxd& a, const openvdb::BBoxd& b)
{
    double sum = 0;
    for (int i = 0; i < 3; ++i) {
        const double g = std::max({0.0, b.min()[i] - a.max()[i], a.min()[i] - b.max()[i]});
        sum += g * g;
    }
    return std::sqrt(sum);
}

template <int D>
std::vector<SurfacePiece>
pieces(const Surface<D>& s)
{
    const std::size_t n = s.points.size();
    for (std::size_t k = 0; k < s.elements.size(); ++k)
        for (int32_t i : s.elements[k])
            if (i < 0 || std::size_t(i) >= n)
                OPENVDB_THROW(openvdb::ValueError,
                              "surfacePieces: element " << k << " has a vertex index out of range");
    std::vector<std::size_t> parent(n);
    std::iota(parent.begin(), parent.end(), std::size_t(0));
    for (const auto& e : s.elements)
        for (int a = 1; a < D; ++a) {
            const std::size_t r0 = findRoot(parent, std::size_t(e[0]));
            const std::size_t r1 = findRoot(parent, std::size_t(e[a]));
            if (r0 != r1) parent[std::max(r0, r1)] = std::min(r0, r1);
        }
    // One piece per root, numbered in order of the first element that reaches it.
    std::vector<std::size_t> pieceOf(n, SIZE_MAX);
    std::vector<SurfacePiece> out;
    std::vector<char> counted(n, 0);
    for (std::size_t k = 0; k < s.elements.size(); ++k) {
        const auto& e = s.elements[k];
        const std::size_t root = findRoot(parent, std::size_t(e[0]));
        if (pieceOf[root] == SIZE_MAX) {
            pieceOf[root] = out.size();
            out.emplace_back();
            out.back().first = k;
        }
        SurfacePiece& p = out[pieceOf[root]];
        ++p.elements;
        p.measure += elementMeasure(s, e);
        for (int32_t i : e) {
            if (counted[std::size_t(i)]) continue;
            counted[std::size_t(i)] = 1;
            ++p.vertices;
            const Vec<D>& x = s.points[std::size_t(i)];
            p.box.expand(openvdb::Vec3d(x[0], x[1], D == 3 ? x[D - 1] : 0.0));
        }
    }
    std::stable_sort(out.begin(), out.end(), [](const SurfacePiece& a, const SurfacePiece& b) {
        return a.measure > b.measure;
    });
    return out;
}

template <int D>
SmallPieces
small(const Surface<D>& s, double share)
{
    if (!(share > 0 && share < 1))
        OPENVDB_THROW(openvdb::ValueError, "smallPieces: share must be in (0, 1)");
    const std::vector<SurfacePiece> all = pieces(s);
    SmallPieces out;
    out.pieces = all.size();
    double total = 0;
    for (const SurfacePiece& p : all)
        total += p.measure;
    if (all.size() < 2 || !(total > 0)) return out;
    for (std::size_t k = 1; k < all.size(); ++k) {
        if (all[k].measure >= share * total) continue;
        ++out.small;
        out.smallVertices += all[k].vertices;
        out.smallShare += all[k].measure / total;
        out.farthest = std::max(out.farthest, boxGap(all[0].box, all[k].box));
    }
    return out;
}

} // namespace

template <>
std::vector<SurfacePiece>
surfacePieces<2>(const Surface<2>& s)
{
    return pieces(s);
}
template <>
std::vector<SurfacePiece>
surfacePieces<3>(const Surface<3>& s)
{
    return pieces(s);
}
template <>
SmallPieces
smallPieces<2>(const Surface<2>& s, double share)
{
    return small(s, share);
}
template <>
SmallPieces
smallPieces<3>(const Surface<3>& s, double share)
{
    return small(s, share);
}

} // namespace vdbmatch
