/// @file SurfaceExtraction.cc
/// @brief Zero level sets of grids as triangle meshes (volumeToMesh) and curves (marching squares).
#include "SurfaceExtraction.h"

#include <openvdb/tools/VolumeToMesh.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

namespace vdbmatch {

Surface<3>
extractSurface(const openvdb::FloatGrid& levelSet)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(levelSet, points, triangles, quads, /*isovalue=*/0.0,
                                 /*adaptivity=*/0.0);
    if (points.empty() || (triangles.empty() && quads.empty())) {
        OPENVDB_THROW(openvdb::ValueError, "extractSurface: grid '" + levelSet.getName() +
                                               "' has an empty zero level set");
    }
    Surface<3> s;
    s.points.reserve(points.size());
    for (const openvdb::Vec3s& p : points)
        s.points.emplace_back(double(p[0]), double(p[1]), double(p[2]));
    s.elements.reserve(triangles.size() + 2 * quads.size());
    auto add = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (a == b || b == c || a == c) return;
        s.elements.push_back({int32_t(a), int32_t(b), int32_t(c)});
    };
    for (const openvdb::Vec3I& t : triangles)
        add(t[0], t[1], t[2]);
    for (const openvdb::Vec4I& q : quads) {
        add(q[0], q[1], q[2]);
        add(q[0], q[2], q[3]);
    }
    return s;
}

bool
isSlice(const openvdb::FloatGrid& grid)
{
    if (grid.tree().activeTileCount() > 0 || grid.tree().activeVoxelCount() == 0) return false;
    const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
    return box.min()[2] == box.max()[2];
}

namespace {

/// Edge e of a cell, in counter-clockwise order: corner c_e -> c_{e+1} with the corners
/// c0 = (i, j), c1 = (i+1, j), c2 = (i+1, j+1), c3 = (i, j+1).
constexpr int CORNER_DX[4] = {0, 1, 1, 0};
constexpr int CORNER_DY[4] = {0, 0, 1, 1};

} // namespace

Surface<2>
extractCurve(const openvdb::FloatGrid& slice)
{
    const std::string where = "extractCurve: grid '" + slice.getName() + "'";
    if (!isSlice(slice)) {
        OPENVDB_THROW(openvdb::ValueError,
                      where + " is not a slice (its active voxels must all have the same k)");
    }
    const int k = slice.evalActiveVoxelBoundingBox().min()[2];
    const auto acc = slice.getConstAccessor();

    // Cells (lower corner) that touch an active voxel, sorted y-major.
    std::vector<std::array<int, 2>> cells;
    for (auto it = slice.tree().cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        for (int dy = -1; dy <= 0; ++dy)
            for (int dx = -1; dx <= 0; ++dx)
                cells.push_back({c[1] + dy, c[0] + dx});
    }
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());

    Surface<2> s;
    // Vertex of the edge from node (i, j) along axis a (0: x, 1: y), one map per axis, keyed by
    // (i, j) packed in 64 bits.
    std::unordered_map<uint64_t, int32_t> edgeVertex[2];
    const openvdb::math::Transform& xform = slice.transform();
    auto vertex = [&](int i, int j, int axis, float v0, float v1) -> int32_t {
        const uint64_t key = (uint64_t(uint32_t(i)) << 32) | uint64_t(uint32_t(j));
        const auto found = edgeVertex[axis].find(key);
        if (found != edgeVertex[axis].end()) return found->second;
        const double t = double(v0) / (double(v0) - double(v1));
        openvdb::Vec3d index(i, j, k);
        index[axis] += t;
        const openvdb::Vec3d w = xform.indexToWorld(index);
        s.points.emplace_back(w[0], w[1]);
        const int32_t id = int32_t(s.points.size() - 1);
        edgeVertex[axis].emplace(key, id);
        return id;
    };

    for (const auto& cell : cells) {
        const int j = cell[0], i = cell[1];
        float v[4];
        bool in[4];
        int insideCount = 0;
        for (int c = 0; c < 4; ++c) {
            v[c] = acc.getValue(openvdb::Coord(i + CORNER_DX[c], j + CORNER_DY[c], k));
            in[c] = v[c] < 0.0f;
            insideCount += in[c] ? 1 : 0;
        }
        if (insideCount == 0 || insideCount == 4) continue;
        // Crossings on the edges in counter-clockwise order; entering[e]: out -> in.
        int32_t id[4] = {-1, -1, -1, -1};
        bool entering[4] = {false, false, false, false};
        for (int e = 0; e < 4; ++e) {
            const int a = e, b = (e + 1) % 4;
            if (in[a] == in[b]) continue;
            entering[e] = in[b];
            // The shared vertex is keyed by the edge's lower node, interpolated from it.
            const bool forward = e < 2; // edges 0, 1 run along +x, +y; 2, 3 along -x, -y
            const int lo = forward ? a : b, hi = forward ? b : a;
            const int axis = (e % 2 == 0) ? 0 : 1;
            id[e] = vertex(i + CORNER_DX[lo], j + CORNER_DY[lo], axis, v[lo], v[hi]);
        }
        // Each segment runs from a leaving crossing (in -> out) to an entering one, keeping the
        // inside on its left. With two crossings the pairing is unique; with four (a saddle),
        // "separate" pairs each leaving crossing with the preceding entering one (cutting off
        // the inside corners), "joined" with the following one.
        bool joined = false;
        if (insideCount == 2 && in[0] == in[2]) {
            const double a = v[0], b = v[1], c = v[2], d = v[3];
            const double denom = a + c - b - d;
            const double saddle = denom != 0.0 ? (a * c - b * d) / denom : 0.25 * (a + b + c + d);
            joined = saddle < 0.0;
        }
        for (int e = 0; e < 4; ++e) {
            if (id[e] < 0 || entering[e]) continue;
            for (int step = 1; step < 4; ++step) {
                const int f = joined ? (e + step) % 4 : (e + 4 - step) % 4;
                if (id[f] >= 0 && entering[f]) {
                    s.elements.push_back({id[e], id[f]});
                    break;
                }
            }
        }
    }
    if (s.elements.empty()) {
        OPENVDB_THROW(openvdb::ValueError, where + " has an empty zero level set");
    }
    return s;
}

} // namespace vdbmatch
