/// @file UnitBox.cc
/// @brief Placement of the shapes in Omega and resampling of level sets as distances in Omega.
#include "UnitBox.h"

#include <openvdb/math/Proximity.h>
#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace vdbmatch {

namespace {

/// Levels accepted by resampleToUnitBox, as SimplexLattice.
constexpr int MIN_LEVEL = 1;
constexpr int MAX_LEVEL = 12;

/// A surface point is at most half a voxel diagonal from the nearest voxel centre.
const double HALF_VOXEL_DIAGONAL = 0.5 * std::sqrt(3.0);

/// meshToVolume with its default post-processing. Its eikonal renormalization matters: without
/// it the narrow band of a sphere had isolated errors of half a voxel (with it, < 0.15 voxel).
constexpr int MESH_TO_VOLUME_FLAGS = 0;

/// A polygon mesh in the index space of the output grid; polygons are quads or triangles
/// (fourth index util::INVALID_IDX), with the polygons around each vertex.
struct Mesh
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec4I> polygons;
    std::vector<uint32_t> vertexPolygonsBegin; ///< CSR over points into vertexPolygons
    std::vector<int32_t> vertexPolygons;

    int corners(int32_t n) const
    {
        return polygons[size_t(n)][3] == openvdb::util::INVALID_IDX ? 3 : 4;
    }

    void buildAdjacency()
    {
        vertexPolygonsBegin.assign(points.size() + 1, 0);
        for (size_t n = 0; n < polygons.size(); ++n) {
            for (int c = 0; c < corners(int32_t(n)); ++c)
                ++vertexPolygonsBegin[polygons[n][c] + 1];
        }
        for (size_t v = 0; v < points.size(); ++v) {
            vertexPolygonsBegin[v + 1] += vertexPolygonsBegin[v];
        }
        vertexPolygons.resize(vertexPolygonsBegin.back());
        std::vector<uint32_t> fill(vertexPolygonsBegin.begin(), vertexPolygonsBegin.end() - 1);
        for (size_t n = 0; n < polygons.size(); ++n) {
            for (int c = 0; c < corners(int32_t(n)); ++c) {
                vertexPolygons[fill[polygons[n][c]]++] = int32_t(n);
            }
        }
    }

    /// Squared distance from p to polygon n; a quad is split into (0,1,2) and (0,2,3), as in
    /// tools::meshToVolume. @a onBoundary tells whether the nearest point lies on the boundary
    /// of the polygon (an edge or a corner, not the diagonal of a quad).
    double distanceSqr(int32_t n, const openvdb::Vec3d& p, bool& onBoundary) const
    {
        // Barycentric weights below this count as 0 (the nearest point is on an edge).
        constexpr double EDGE_WEIGHT = 1e-9;
        const openvdb::Vec4I& poly = polygons[size_t(n)];
        const openvdb::Vec3d a(points[poly[0]]), b(points[poly[1]]), c(points[poly[2]]);
        openvdb::Vec3d uvw;
        double d = (p - openvdb::math::closestPointOnTriangleToPoint(a, b, c, p, uvw)).lengthSqr();
        if (poly[3] == openvdb::util::INVALID_IDX) {
            onBoundary = uvw.x() < EDGE_WEIGHT || uvw.y() < EDGE_WEIGHT || uvw.z() < EDGE_WEIGHT;
            return d;
        }
        // Quad: in (a, b, c) the edge ac (weight of b = 0) is the interior diagonal.
        onBoundary = uvw.x() < EDGE_WEIGHT || uvw.z() < EDGE_WEIGHT;
        const openvdb::Vec3d e(points[poly[3]]);
        const double d2 =
            (p - openvdb::math::closestPointOnTriangleToPoint(a, c, e, p, uvw)).lengthSqr();
        if (d2 < d) {
            d = d2;
            onBoundary = uvw.x() < EDGE_WEIGHT || uvw.y() < EDGE_WEIGHT;
        }
        return d;
    }

    /// Greedy descent over the mesh from polygon @a n, at squared distance @a dSqr from p: while
    /// the nearest point of the current polygon lies on its boundary, moves to the nearest
    /// polygon sharing a vertex with it if that is nearer. Ties go to the lower index, so the
    /// result is deterministic.
    /// @note When the nearest point is inside the polygon, a polygon next to it can only be
    /// nearer where the surface curves towards p, by O(polygon size^2 * curvature); that
    /// second-order error is accepted to avoid searching the neighbourhood of every voxel.
    void descend(const openvdb::Vec3d& p, int32_t& n, double& dSqr, bool onBoundary) const
    {
        for (int step = 0; step < MAX_DESCENT_STEPS && onBoundary; ++step) {
            const int32_t current = n;
            std::array<int32_t, MAX_VISITED> visited;
            size_t numVisited = 0;
            for (int c = 0; c < corners(current); ++c) {
                const uint32_t v = polygons[size_t(current)][c];
                for (uint32_t k = vertexPolygonsBegin[v]; k < vertexPolygonsBegin[v + 1]; ++k) {
                    const int32_t q = vertexPolygons[k];
                    if (q == current || std::find(visited.begin(), visited.begin() + numVisited,
                                                  q) != visited.begin() + numVisited) {
                        continue;
                    }
                    if (numVisited < MAX_VISITED) visited[numVisited++] = q;
                    bool qOnBoundary = false;
                    const double d = distanceSqr(q, p, qOnBoundary);
                    if (d < dSqr || (d == dSqr && q < n)) {
                        dSqr = d;
                        n = q;
                        onBoundary = qOnBoundary;
                    }
                }
            }
            if (n == current) return;
        }
    }

    /// Bound on the descent steps: the start is the polygon nearest to a neighbouring voxel, at
    /// most a few polygons away from the nearest one.
    static constexpr int MAX_DESCENT_STEPS = 64;
    /// Polygons remembered per step to skip repeats (a vertex of a volumeToMesh mesh has a
    /// handful of polygons; beyond this, repeats are merely evaluated twice).
    static constexpr size_t MAX_VISITED = 32;
};

/// Dense index of the node box [lo, lo + n)^3.
struct NodeBox
{
    int lo, n;
    size_t size() const { return size_t(n) * size_t(n) * size_t(n); }
    bool contains(const openvdb::Coord& c) const
    {
        return c[0] >= lo && c[1] >= lo && c[2] >= lo && c[0] < lo + n && c[1] < lo + n &&
               c[2] < lo + n;
    }
    size_t index(const openvdb::Coord& c) const
    {
        return size_t(c[0] - lo) + size_t(n) * (size_t(c[1] - lo) + size_t(n) * size_t(c[2] - lo));
    }
    openvdb::Coord coord(size_t i) const
    {
        const size_t nn = size_t(n);
        return openvdb::Coord(lo + int(i % nn), lo + int((i / nn) % nn), lo + int(i / (nn * nn)));
    }
};

/// Sets every voxel of the node box of @a level that is not active in @a grid to its signed
/// distance to @a mesh, layer by layer outwards from the active voxels: a new voxel starts from
/// the nearest of the polygons closest to its 26 already known neighbours and descends over the
/// mesh to the nearest polygon (Mesh::descend). The sign is that of the voxel's (flood-filled)
/// inactive value. The values do not depend on the order of the voxels in a layer or on the
/// thread count. Returns false if interrupted.
/// @throw openvdb::ValueError if no active voxel of @a grid lies in the box.
bool
fillNodeBox(openvdb::FloatGrid& grid, const openvdb::Int32Grid& polygonIndex, const Mesh& mesh,
            int level, openvdb::util::NullInterrupter& interrupt)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const double h = grid.voxelSize()[0];
    const NodeBox box{-UNIT_BOX_NODE_PADDING, (1 << level) + 2 * UNIT_BOX_NODE_PADDING + 1};
    constexpr uint8_t UNKNOWN = 0, KNOWN = 1, QUEUED = 2;
    std::unique_ptr<std::atomic<uint8_t>[]> state(new std::atomic<uint8_t>[box.size()]);
    std::vector<float> dist(box.size(), 0.0f); // unsigned, index units
    std::vector<int32_t> closest(box.size(), -1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, box.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              state[i] = UNKNOWN;
                      });

    // Seeds: the active voxels (narrow band) inside the box.
    const auto indexAcc = polygonIndex.getConstAccessor();
    const int32_t polygonCount = int32_t(mesh.polygons.size());
    std::vector<size_t> frontier;
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
        const openvdb::Coord ijk = it.getCoord();
        if (!it.isVoxelValue() || !box.contains(ijk)) continue;
        const size_t i = box.index(ijk);
        state[i] = KNOWN;
        dist[i] = float(std::abs(*it) / h);
        const int32_t poly = indexAcc.getValue(ijk);
        closest[i] = poly >= 0 && poly < polygonCount ? poly : -1;
        frontier.push_back(i);
    }
    if (frontier.empty()) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: the placed surface does not meet "
                                           "the unit box");
    }
    std::array<openvdb::Coord, 26> offsets;
    for (int k = 0, o = 0; k < 27; ++k) {
        if (k != 13) offsets[o++] = openvdb::Coord(k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1);
    }

    // Layers: queue the unknown neighbours of the last layer (in parallel; the set does not
    // depend on the order), then compute them from the known voxels only.
    tbb::enumerable_thread_specific<std::vector<size_t>> queued;
    std::vector<float> newDist;
    std::vector<int32_t> newClosest;
    while (true) {
        for (auto& q : queued)
            q.clear();
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, frontier.size()),
            [&](const tbb::blocked_range<size_t>& r) {
                std::vector<size_t>& out = queued.local();
                for (size_t f = r.begin(); f != r.end(); ++f) {
                    const openvdb::Coord ijk = box.coord(frontier[f]);
                    for (const openvdb::Coord& o : offsets) {
                        const openvdb::Coord nb = ijk + o;
                        if (!box.contains(nb)) continue;
                        uint8_t expected = UNKNOWN;
                        if (state[box.index(nb)].compare_exchange_strong(expected, QUEUED)) {
                            out.push_back(box.index(nb));
                        }
                    }
                }
            });
        frontier.clear();
        for (const auto& q : queued)
            frontier.insert(frontier.end(), q.begin(), q.end());
        if (frontier.empty()) break;
        if (interrupt.wasInterrupted()) return false;
        newDist.resize(frontier.size());
        newClosest.resize(frontier.size());
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, frontier.size()),
            [&](const tbb::blocked_range<size_t>& r) {
                for (size_t f = r.begin(); f != r.end(); ++f) {
                    const openvdb::Coord ijk = box.coord(frontier[f]);
                    const openvdb::Vec3d p(ijk.asVec3d());
                    std::array<int32_t, 26> tried;
                    int numTried = 0;
                    double best = std::numeric_limits<double>::max();
                    int32_t bestPoly = -1;
                    bool onBoundary = false;
                    // Fallback when no neighbour knows a polygon: a path length bound.
                    double bound = std::numeric_limits<double>::max();
                    for (const openvdb::Coord& o : offsets) {
                        const openvdb::Coord nb = ijk + o;
                        if (!box.contains(nb)) continue;
                        const size_t j = box.index(nb);
                        if (state[j] != KNOWN) continue;
                        bound = std::min(bound, double(dist[j]) + o.asVec3d().length());
                        const int32_t poly = closest[j];
                        if (poly < 0 || std::find(tried.begin(), tried.begin() + numTried, poly) !=
                                            tried.begin() + numTried) {
                            continue;
                        }
                        tried[size_t(numTried++)] = poly;
                        bool polyOnBoundary = false;
                        const double d = mesh.distanceSqr(poly, p, polyOnBoundary);
                        if (d < best || (d == best && poly < bestPoly)) {
                            best = d;
                            bestPoly = poly;
                            onBoundary = polyOnBoundary;
                        }
                    }
                    if (bestPoly >= 0) mesh.descend(p, bestPoly, best, onBoundary);
                    newDist[f] = float(bestPoly >= 0 ? std::sqrt(best) : bound);
                    newClosest[f] = bestPoly;
                }
            });
        for (size_t f = 0; f < frontier.size(); ++f) {
            state[frontier[f]] = KNOWN;
            dist[frontier[f]] = newDist[f];
            closest[frontier[f]] = newClosest[f];
        }
    }

    // Write the box into the grid: allocate its leaves (keeping values and states), then set
    // the inactive voxels of each leaf in parallel.
    std::vector<LeafT*> leaves;
    const openvdb::Coord first = openvdb::Coord(box.lo) & ~int(LeafT::DIM - 1);
    const int last = box.lo + box.n - 1;
    for (int z = first[2]; z <= last; z += LeafT::DIM)
        for (int y = first[1]; y <= last; y += LeafT::DIM)
            for (int x = first[0]; x <= last; x += LeafT::DIM)
                leaves.push_back(grid.tree().touchLeaf(openvdb::Coord(x, y, z)));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t l = r.begin(); l != r.end(); ++l) {
                              LeafT& leaf = *leaves[l];
                              for (openvdb::Index off = 0; off < LeafT::SIZE; ++off) {
                                  const openvdb::Coord ijk = leaf.offsetToGlobalCoord(off);
                                  if (!box.contains(ijk) || leaf.isValueOn(off)) continue;
                                  const float sign = leaf.getValue(off) < 0.0f ? -1.0f : 1.0f;
                                  leaf.setValueOn(off, sign * float(dist[box.index(ijk)] * h));
                              }
                          }
                      });
    return true;
}

} // namespace

UnitBoxPlacement
UnitBoxPlacement::fromWorldBox(const openvdb::BBoxd& worldBox, double margin)
{
    if (!(margin >= 0.0 && margin < 0.5)) {
        std::ostringstream s;
        s << "UnitBoxPlacement::fromWorldBox: margin must be in [0, 0.5), got " << margin;
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    const openvdb::Vec3d extents = worldBox.extents();
    const double side = std::max({extents[0], extents[1], extents[2]});
    bool finite = true;
    for (int a = 0; a < 3; ++a) {
        finite = finite && std::isfinite(worldBox.min()[a]) && std::isfinite(worldBox.max()[a]);
    }
    if (!finite || worldBox.empty() || !(side > 0.0)) {
        std::ostringstream s;
        s << "UnitBoxPlacement::fromWorldBox: expected a non-degenerate finite box, got "
          << worldBox;
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    UnitBoxPlacement p;
    p.margin = margin;
    p.worldBox = worldBox;
    p.scale = (1.0 - 2.0 * margin) / side;
    p.worldOrigin = worldBox.getCenter() - openvdb::Vec3d(0.5 / p.scale);
    return p;
}

openvdb::BBoxd
zeroLevelSetWorldBox(const openvdb::FloatGrid& levelSet)
{
    const openvdb::math::Transform& xform = levelSet.transform();
    const double h = levelSet.voxelSize()[0];
    const float threshold = float(h);
    openvdb::BBoxd box; // empty: min = +max, max = -max
    bool found = false;
    for (auto it = levelSet.tree().cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue() || !(std::abs(*it) <= threshold)) continue;
        const openvdb::Vec3d w = xform.indexToWorld(it.getCoord());
        if (!found) box = openvdb::BBoxd(w, w);
        box.expand(w);
        found = true;
    }
    if (!found) {
        OPENVDB_THROW(openvdb::ValueError, "zeroLevelSetWorldBox: grid '" + levelSet.getName() +
                                               "' has no active voxel within one voxel of its "
                                               "zero level set");
    }
    box.expand(HALF_VOXEL_DIAGONAL * h);
    return box;
}

UnitBoxPlacement
placeInUnitBox(const openvdb::FloatGrid& source, const openvdb::FloatGrid& target, double margin)
{
    openvdb::BBoxd box = zeroLevelSetWorldBox(source);
    box.expand(zeroLevelSetWorldBox(target));
    return UnitBoxPlacement::fromWorldBox(box, margin);
}

openvdb::FloatGrid::Ptr
resampleToUnitBox(const openvdb::FloatGrid& levelSet, const UnitBoxPlacement& placement, int level,
                  double bandWidthVoxels, openvdb::util::NullInterrupter* interrupter)
{
    if (level < MIN_LEVEL || level > MAX_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError,
                      "resampleToUnitBox: level must be in [" + std::to_string(MIN_LEVEL) + ", " +
                          std::to_string(MAX_LEVEL) + "], got " + std::to_string(level));
    }
    if (!(bandWidthVoxels >= MIN_RESAMPLE_BAND_VOXELS) || !std::isfinite(bandWidthVoxels)) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: bandWidthVoxels must be finite and "
                                           ">= 3, got " +
                                               std::to_string(bandWidthVoxels));
    }
    if (!(placement.scale > 0.0) || !std::isfinite(placement.scale)) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: invalid placement scale " +
                                               std::to_string(placement.scale));
    }
    openvdb::util::NullInterrupter nullInterrupter;
    openvdb::util::NullInterrupter& interrupt = interrupter ? *interrupter : nullInterrupter;
    interrupt.start("resampleToUnitBox");
    struct EndGuard
    {
        openvdb::util::NullInterrupter& i;
        ~EndGuard() { i.end(); }
    } endGuard{interrupt};

    // 1. The zero isosurface, world space.
    Mesh mesh;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(levelSet, mesh.points, triangles, quads, /*isovalue=*/0.0,
                                 /*adaptivity=*/0.0);
    if (mesh.points.empty() || (triangles.empty() && quads.empty())) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: grid '" + levelSet.getName() +
                                               "' has an empty zero level set");
    }
    if (interrupt.wasInterrupted()) return nullptr;

    // 2. Vertices in the index space of the output grid (unit / h), computed in double.
    const double h = std::ldexp(1.0, -level);
    const double worldToIndex = placement.scale / h;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              const openvdb::Vec3d w(mesh.points[i]);
                              mesh.points[i] =
                                  openvdb::Vec3s((w - placement.worldOrigin) * worldToIndex);
                          }
                      });
    mesh.polygons.reserve(triangles.size() + quads.size());
    for (const openvdb::Vec3I& t : triangles) {
        mesh.polygons.emplace_back(t[0], t[1], t[2], openvdb::util::INVALID_IDX);
    }
    mesh.polygons.insert(mesh.polygons.end(), quads.begin(), quads.end());
    triangles = {};
    quads = {};
    mesh.buildAdjacency();

    // 3. Narrow band of the distance to the mesh, with the closest polygon of every voxel.
    const openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec4I> adapter(
        mesh.points, mesh.polygons);
    const openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(h);
    openvdb::Int32Grid polygonIndex;
    openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        interrupt, adapter, *xform, float(bandWidthVoxels), float(bandWidthVoxels),
        MESH_TO_VOLUME_FLAGS, &polygonIndex);
    if (interrupt.wasInterrupted()) return nullptr;

    // 4. Every node of the padded unit box.
    if (!fillNodeBox(*grid, polygonIndex, mesh, level, interrupt)) return nullptr;
    float maxAbs = float(bandWidthVoxels * h);
    for (auto it = grid->tree().cbeginValueOn(); it; ++it)
        maxAbs = std::max(maxAbs, std::abs(*it));
    openvdb::tools::changeLevelSetBackground(grid->tree(), maxAbs);

    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    return grid;
}

bool
coversUnitBoxNodes(const openvdb::FloatGrid& grid, int level, int padding)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const int n = 1 << level;
    const openvdb::CoordBBox nodes(openvdb::Coord(-padding), openvdb::Coord(n + padding));
    // Visit the box leaf by leaf: a missing leaf means inactive voxels (level sets have no
    // active tiles, and tiles are treated as uncovered).
    const openvdb::Coord first = nodes.min() & ~(LeafT::DIM - 1);
    const openvdb::FloatTree& tree = grid.tree();
    for (int x = first[0]; x <= nodes.max()[0]; x += LeafT::DIM) {
        for (int y = first[1]; y <= nodes.max()[1]; y += LeafT::DIM) {
            for (int z = first[2]; z <= nodes.max()[2]; z += LeafT::DIM) {
                const openvdb::Coord origin(x, y, z);
                const LeafT* leaf = tree.probeConstLeaf(origin);
                if (!leaf) return false;
                openvdb::CoordBBox part(origin, origin.offsetBy(LeafT::DIM - 1));
                part.intersect(nodes);
                if (part.volume() == LeafT::SIZE) {
                    if (!leaf->getValueMask().isOn()) return false;
                    continue;
                }
                for (auto ijk = part.begin(); ijk; ++ijk) {
                    if (!leaf->isValueOn(*ijk)) return false;
                }
            }
        }
    }
    return true;
}

} // namespace vdbmatch
