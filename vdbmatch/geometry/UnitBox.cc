/// @file UnitBox.cc
/// @brief Placement of the shapes in Omega and resampling of level sets as distances in Omega.
#include "UnitBox.h"

#include "Surface.h"
#include "TriangleDistance.h"

#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
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

/// A short list of distinct polygon indices, to skip repeated distance evaluations. When full,
/// insert() accepts everything (a repeat is then merely evaluated twice).
class PolygonList
{
public:
    /// Adds n; false if it was already listed.
    bool insert(int32_t n)
    {
        const auto end = mItems.begin() + std::ptrdiff_t(mSize);
        if (std::find(mItems.begin(), end, n) != end) return false;
        if (mSize < CAPACITY) mItems[mSize++] = n;
        return true;
    }

private:
    /// The polygons of 26 neighbours plus a few descent steps.
    static constexpr size_t CAPACITY = 64;
    std::array<int32_t, CAPACITY> mItems;
    size_t mSize = 0;
};

/// A polygon mesh in the index space of the output grid: quads or triangles (fourth index
/// util::INVALID_IDX), with the corners of each polygon in double precision and the polygons
/// around each vertex.
class Mesh
{
public:
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec4I> polygons;

    /// Builds the tables used by distanceSqr() and descend(); call after filling points and
    /// polygons.
    void finalize()
    {
        mCorners.resize(polygons.size() * 4);
        mVertexBegin.assign(points.size() + 1, 0);
        for (size_t n = 0; n < polygons.size(); ++n) {
            const int count = corners(n);
            for (int c = 0; c < 4; ++c) {
                mCorners[n * 4 + size_t(c)] = openvdb::Vec3d(points[polygons[n][c % count]]);
            }
            for (int c = 0; c < count; ++c)
                ++mVertexBegin[polygons[n][c] + 1];
        }
        for (size_t v = 0; v < points.size(); ++v)
            mVertexBegin[v + 1] += mVertexBegin[v];
        mVertexPolygons.resize(mVertexBegin.back());
        std::vector<uint32_t> next(mVertexBegin.begin(), mVertexBegin.end() - 1);
        for (size_t n = 0; n < polygons.size(); ++n) {
            for (int c = 0; c < corners(n); ++c) {
                mVertexPolygons[next[polygons[n][c]]++] = int32_t(n);
            }
        }
    }

    /// Squared distance from p to polygon n; a quad is split into (0,1,2) and (0,2,3), as in
    /// tools::meshToVolume.
    double distanceSqr(int32_t n, const openvdb::Vec3d& p) const
    {
        const openvdb::Vec3d* c = &mCorners[size_t(n) * 4];
        const double d = detail::triangleDistanceSqr(p, c[0], c[1], c[2]);
        return isQuad(size_t(n)) ? std::min(d, detail::triangleDistanceSqr(p, c[0], c[2], c[3]))
                                 : d;
    }

    /// Steepest descent over the mesh from polygon @a n at squared distance @a dSqr from p:
    /// moves to the nearest polygon sharing a vertex with the current one while that is nearer,
    /// i.e. to a local minimum of the distance over the mesh. Ties go to the lower index, so the
    /// result is deterministic. Polygons in @a evaluated (already compared with @a n) are
    /// skipped; the polygons evaluated here are added.
    void descend(const openvdb::Vec3d& p, int32_t& n, double& dSqr, PolygonList& evaluated) const
    {
        for (int step = 0; step < MAX_DESCENT_STEPS; ++step) {
            const int32_t current = n;
            for (int c = 0; c < corners(size_t(current)); ++c) {
                const uint32_t v = polygons[size_t(current)][c];
                for (uint32_t k = mVertexBegin[v]; k < mVertexBegin[v + 1]; ++k) {
                    const int32_t q = mVertexPolygons[k];
                    if (q == current || !evaluated.insert(q)) continue;
                    const double d = distanceSqr(q, p);
                    if (d < dSqr || (d == dSqr && q < n)) {
                        dSqr = d;
                        n = q;
                    }
                }
            }
            if (n == current) return;
        }
    }

private:
    bool isQuad(size_t n) const { return polygons[n][3] != openvdb::util::INVALID_IDX; }
    int corners(size_t n) const { return isQuad(n) ? 4 : 3; }

    /// Bound on the descent steps: the start is the polygon nearest to a neighbouring voxel, a
    /// few polygons from the nearest one.
    static constexpr int MAX_DESCENT_STEPS = 64;
    std::vector<openvdb::Vec3d> mCorners; ///< 4 per polygon (a triangle repeats corner 0)
    std::vector<uint32_t> mVertexBegin;   ///< CSR over points into mVertexPolygons
    std::vector<int32_t> mVertexPolygons;
};

/// The node box [lo, lo + n)^3 as a dense array, x fastest.
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
    /// True if the 26 neighbours of c are all in the box.
    bool isInterior(const openvdb::Coord& c) const
    {
        return c[0] > lo && c[1] > lo && c[2] > lo && c[0] < lo + n - 1 && c[1] < lo + n - 1 &&
               c[2] < lo + n - 1;
    }
};

/// The 26 neighbour offsets and their index offsets in a NodeBox.
struct Neighbours
{
    std::array<openvdb::Coord, 26> offset;
    std::array<std::ptrdiff_t, 26> delta;
    std::array<double, 26> length;

    explicit Neighbours(const NodeBox& box)
    {
        const std::ptrdiff_t n = box.n;
        for (int k = 0, o = 0; k < 27; ++k) {
            if (k == 13) continue; // the centre
            offset[o] = openvdb::Coord(k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1);
            delta[o] = offset[o][0] + n * (offset[o][1] + n * offset[o][2]);
            length[o] = offset[o].asVec3d().length();
            ++o;
        }
    }
};

/// Sets every voxel of the node box of @a level that is not active in @a grid to its signed
/// distance to @a mesh, layer by layer outwards from the active voxels: a new voxel starts from
/// the nearest of the polygons closest to its 26 already known neighbours and descends over the
/// mesh to the nearest polygon (Mesh::descend). The sign is that of the voxel's (flood-filled)
/// inactive value. The values do not depend on the thread count. Returns false if interrupted.
/// @throw openvdb::ValueError if no active voxel of @a grid lies in the box.
bool
fillNodeBox(openvdb::FloatGrid& grid, const openvdb::Int32Grid& polygonIndex, const Mesh& mesh,
            int level, openvdb::util::NullInterrupter& interrupt)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const double h = grid.voxelSize()[0];
    const NodeBox box{-UNIT_BOX_NODE_PADDING, (1 << level) + 2 * UNIT_BOX_NODE_PADDING + 1};
    const Neighbours nbs(box);
    constexpr uint8_t UNKNOWN = 0, KNOWN = 1, QUEUED = 2;
    std::vector<uint8_t> state(box.size(), UNKNOWN);
    std::vector<float> dist(box.size(), 0.0f); // unsigned, index units
    std::vector<int32_t> closest(box.size(), -1);

    // Seeds: the active voxels (narrow band) inside the box.
    const auto indexAcc = polygonIndex.getConstAccessor();
    const int32_t polygonCount = int32_t(mesh.polygons.size());
    std::vector<size_t> frontier;
    for (auto it = grid.tree().cbeginValueOn(); it; ++it) {
        const openvdb::Coord ijk = it.getCoord();
        if (!it.isVoxelValue() || !box.contains(ijk)) continue;
        const size_t i = box.index(ijk);
        state[i] = KNOWN;
        dist[i] = float(std::abs(double(*it)) / h);
        const int32_t poly = indexAcc.getValue(ijk);
        closest[i] = poly >= 0 && poly < polygonCount ? poly : -1;
        frontier.push_back(i);
    }
    if (frontier.empty()) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: the placed surface does not meet "
                                           "the unit box");
    }

    // Distance of voxel i from the polygons nearest to its known neighbours, improved by
    // descent over the mesh; reads only voxels of earlier layers.
    auto nearestPolygon = [&](size_t i, float& outDist, int32_t& outPolygon) {
        const openvdb::Coord ijk = box.coord(i);
        const openvdb::Vec3d p(ijk.asVec3d());
        const bool interior = box.isInterior(ijk);
        PolygonList evaluated;
        double best = std::numeric_limits<double>::max();
        int32_t bestPoly = -1;
        double bound = std::numeric_limits<double>::max(); // if no neighbour knows a polygon
        for (int k = 0; k < 26; ++k) {
            if (!interior && !box.contains(ijk + nbs.offset[k])) continue;
            const size_t j = size_t(std::ptrdiff_t(i) + nbs.delta[k]);
            if (state[j] != KNOWN) continue;
            bound = std::min(bound, double(dist[j]) + nbs.length[k]);
            const int32_t poly = closest[j];
            if (poly < 0 || !evaluated.insert(poly)) continue;
            const double d = mesh.distanceSqr(poly, p);
            if (d < best || (d == best && poly < bestPoly)) {
                best = d;
                bestPoly = poly;
            }
        }
        if (bestPoly >= 0) mesh.descend(p, bestPoly, best, evaluated);
        outDist = float(bestPoly >= 0 ? std::sqrt(best) : bound);
        outPolygon = bestPoly;
    };

    // Layers: queue the unknown neighbours of the last layer, then compute them in parallel from
    // the known voxels only.
    std::vector<size_t> next;
    std::vector<float> newDist;
    std::vector<int32_t> newClosest;
    while (true) {
        next.clear();
        for (const size_t i : frontier) {
            const openvdb::Coord ijk = box.coord(i);
            const bool interior = box.isInterior(ijk);
            for (int k = 0; k < 26; ++k) {
                if (!interior && !box.contains(ijk + nbs.offset[k])) continue;
                const size_t j = size_t(std::ptrdiff_t(i) + nbs.delta[k]);
                if (state[j] != UNKNOWN) continue;
                state[j] = QUEUED;
                next.push_back(j);
            }
        }
        if (next.empty()) break;
        if (interrupt.wasInterrupted()) return false;
        frontier.swap(next);
        newDist.resize(frontier.size());
        newClosest.resize(frontier.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, frontier.size()),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t f = r.begin(); f != r.end(); ++f) {
                                  nearestPolygon(frontier[f], newDist[f], newClosest[f]);
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
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, leaves.size()), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t l = r.begin(); l != r.end(); ++l) {
                LeafT& leaf = *leaves[l];
                for (openvdb::Index off = 0; off < LeafT::SIZE; ++off) {
                    const openvdb::Coord ijk = leaf.offsetToGlobalCoord(off);
                    if (!box.contains(ijk) || leaf.isValueOn(off)) continue;
                    const float sign = leaf.getValue(off) < 0.0f ? -1.0f : 1.0f;
                    leaf.setValueOn(off, sign * float(double(dist[box.index(ijk)]) * h));
                }
            }
        });
    return true;
}

} // namespace

UnitBoxPlacement
UnitBoxPlacement::fromWorldBox(const openvdb::BBoxd& worldBox, double margin)
{
    // Finiteness is tested first: ordered comparisons with NaN would raise FE_INVALID.
    if (!std::isfinite(margin) || margin < 0.0 || margin >= 0.5) {
        std::ostringstream s;
        s << "UnitBoxPlacement::fromWorldBox: margin must be in [0, 0.5), got " << margin;
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    bool valid = true;
    for (int a = 0; a < 3; ++a) {
        valid = valid && std::isfinite(worldBox.min()[a]) && std::isfinite(worldBox.max()[a]);
    }
    const openvdb::Vec3d extents = valid ? worldBox.extents() : openvdb::Vec3d(0.0);
    const double side = std::max({extents[0], extents[1], extents[2]});
    const bool empty =
        valid && (worldBox.min()[0] > worldBox.max()[0] || worldBox.min()[1] > worldBox.max()[1] ||
                  worldBox.min()[2] > worldBox.max()[2]);
    if (!valid || empty || !(side > 0.0)) {
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

template <int D>
UnitBoxPlacement
placeInUnitBox(const Surface<D>& source, const Surface<D>& target, double margin)
{
    if (source.points.empty() || target.points.empty()) {
        OPENVDB_THROW(openvdb::ValueError, "placeInUnitBox: a surface has no points");
    }
    openvdb::BBoxd box = boundingBox(source);
    box.expand(boundingBox(target));
    return UnitBoxPlacement::fromWorldBox(box, margin);
}

template UnitBoxPlacement placeInUnitBox<2>(const Surface<2>&, const Surface<2>&, double);
template UnitBoxPlacement placeInUnitBox<3>(const Surface<3>&, const Surface<3>&, double);

openvdb::FloatGrid::Ptr
resampleToUnitBox(const openvdb::FloatGrid& levelSet, const UnitBoxPlacement& placement, int level,
                  double bandWidthVoxels, openvdb::util::NullInterrupter* interrupter)
{
    if (level < MIN_LEVEL || level > MAX_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError,
                      "resampleToUnitBox: level must be in [" + std::to_string(MIN_LEVEL) + ", " +
                          std::to_string(MAX_LEVEL) + "], got " + std::to_string(level));
    }
    if (!std::isfinite(bandWidthVoxels) || bandWidthVoxels < MIN_RESAMPLE_BAND_VOXELS) {
        OPENVDB_THROW(openvdb::ValueError, "resampleToUnitBox: bandWidthVoxels must be finite and "
                                           ">= 3, got " +
                                               std::to_string(bandWidthVoxels));
    }
    if (!std::isfinite(placement.scale) || placement.scale <= 0.0) {
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
    mesh.finalize();

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
