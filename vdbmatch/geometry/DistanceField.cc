/// @file DistanceField.cc
/// @brief Signed distance grids of surfaces on Omega nodes (meshToVolume in 3D, exact tiles with
///        crossing parity in 2D) and the tiered shape sampler.
#include "DistanceField.h"

#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/TriangleDistance.h>

#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace vdbmatch {

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;
/// Nodes per side of a 2D tile: one leaf node's x-y face.
constexpr int TILE = int(LeafT::DIM);
constexpr int TILE_NODES = TILE * TILE;
/// Distance from a tile's centre to its farthest node, in voxels.
const double TILE_RADIUS = 0.5 * (TILE - 1) * std::sqrt(2.0);
/// meshToVolume with its default post-processing (as resampleToUnitBox: its renormalization
/// keeps the band errors below 0.15 voxel on spheres).
constexpr int MESH_TO_VOLUME_FLAGS = 0;
/// Spacing of the sample nodes used to bound the largest distance in the box (distanceBox 3D),
/// and the number of vertices used for that bound at most.
constexpr int BOUND_SAMPLE_SPACING = 4;
constexpr size_t BOUND_MAX_VERTICES = 4096;

void
validate(const char* caller, int level, double halfWidthVoxels)
{
    if (level < MIN_DISTANCE_LEVEL || level > MAX_DISTANCE_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError, std::string(caller) + ": level must be in [" +
                                               std::to_string(MIN_DISTANCE_LEVEL) + ", " +
                                               std::to_string(MAX_DISTANCE_LEVEL) + "], got " +
                                               std::to_string(level));
    }
    if (!std::isfinite(halfWidthVoxels) || halfWidthVoxels < MIN_DISTANCE_HALF_WIDTH_VOXELS) {
        OPENVDB_THROW(openvdb::ValueError, std::string(caller) +
                                               ": half width must be finite and >= 3 voxels, "
                                               "got " +
                                               std::to_string(halfWidthVoxels));
    }
}

int
floorDiv(int a, int b)
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

////////////////////////////////////////////////////////////////////////////////
// 2D: exact distances to segments per tile, sign by crossing parity

/// Segments in index space (node units).
struct Segments2D
{
    std::vector<Vec<2>> a, b;

    size_t size() const { return a.size(); }
    double distanceSqr(size_t s, const Vec<2>& p) const
    {
        return detail::segmentDistanceSqr(p, a[s], b[s]);
    }
};

/// For every row y = j (index units), the sorted x of the crossings of the curves with it.
/// A segment crosses row j iff min(ya, yb) <= j < max(ya, yb) (half-open), so a vertex on the
/// row is counted once when the curve passes through, twice or never when it touches.
class RowCrossings
{
public:
    RowCrossings(const Segments2D& s, bool threaded)
    {
        if (s.size() == 0) return;
        double lo = std::numeric_limits<double>::max(), hi = -lo;
        for (size_t k = 0; k < s.size(); ++k) {
            lo = std::min({lo, s.a[k][1], s.b[k][1]});
            hi = std::max({hi, s.a[k][1], s.b[k][1]});
        }
        mFirst = int(std::ceil(lo));
        const int last = int(std::ceil(hi)) - 1;
        if (last < mFirst) return;
        mRows.resize(size_t(last - mFirst + 1));
        for (size_t k = 0; k < s.size(); ++k) {
            const Vec<2>&p = s.a[k], &q = s.b[k];
            const double y0 = std::min(p[1], q[1]), y1 = std::max(p[1], q[1]);
            if (!(y0 < y1)) continue;
            const double slope = (q[0] - p[0]) / (q[1] - p[1]);
            for (int j = int(std::ceil(y0)); double(j) < y1; ++j) {
                mRows[size_t(j - mFirst)].push_back(p[0] + (double(j) - p[1]) * slope);
            }
        }
        detail::forEachIndex(mRows.size(), threaded,
                             [&](size_t r) { std::sort(mRows[r].begin(), mRows[r].end()); });
    }

    /// Even-odd inside test of node (i, j): an odd number of crossings left of x = i.
    bool isInside(int i, int j) const
    {
        if (j < mFirst || j >= mFirst + int(mRows.size())) return false;
        const std::vector<double>& row = mRows[size_t(j - mFirst)];
        const size_t left =
            size_t(std::lower_bound(row.begin(), row.end(), double(i)) - row.begin());
        return (left & 1u) != 0;
    }

private:
    int mFirst = 0;
    std::vector<std::vector<double>> mRows;
};

/// Signed distances (index units) and activity of the nodes of one tile.
struct TileResult
{
    std::array<float, TILE_NODES> value; ///< signed distance, voxels
    uint64_t active = 0;                 ///< bit x + TILE y
};

/// Computes the tiles with origins (TILE tx, TILE ty) for tx in [tx0, tx1], ty in [ty0, ty1].
/// Band mode (halfWidth finite): nodes with |d| <= halfWidth are active, tiles beyond the band
/// are skipped. Box mode (halfWidth infinite): every node is active.
class TileRasterizer
{
public:
    TileRasterizer(const Segments2D& segments, bool threaded)
        : mSegments(segments), mCrossings(segments, threaded), mThreaded(threaded)
    {
    }

    /// Builds a slice grid k = 0 with transform @a xform; values are index distances times
    /// @a voxel. Returns the grid, level set class, name "surface", background
    /// max(minBackground, largest |value|).
    openvdb::FloatGrid::Ptr build(int tx0, int tx1, int ty0, int ty1, double halfWidth,
                                  double voxel, double minBackground,
                                  const openvdb::math::Transform::Ptr& xform) const
    {
        const size_t nx = size_t(tx1 - tx0 + 1), ny = size_t(ty1 - ty0 + 1);
        std::vector<std::unique_ptr<TileResult>> tiles(nx * ny);
        detail::forEachIndex(tiles.size(), mThreaded, [&](size_t t) {
            const int ox = (tx0 + int(t % nx)) * TILE, oy = (ty0 + int(t / nx)) * TILE;
            tiles[t] = computeTile(ox, oy, halfWidth);
        });
        double maxAbs = 0.0;
        for (const auto& t : tiles) {
            if (!t) continue;
            for (int n = 0; n < TILE_NODES; ++n)
                if ((t->active >> n) & 1u)
                    maxAbs = std::max(maxAbs, double(std::abs(t->value[size_t(n)])));
        }
        const float background = float(std::max(minBackground, maxAbs * voxel));

        openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
        grid->setTransform(xform);
        grid->setGridClass(openvdb::GRID_LEVEL_SET);
        grid->setName("surface");
        std::vector<LeafT*> leaves(tiles.size(), nullptr);
        detail::forEachIndex(tiles.size(), mThreaded, [&](size_t t) {
            if (!tiles[t]) return;
            const int ox = (tx0 + int(t % nx)) * TILE, oy = (ty0 + int(t / nx)) * TILE;
            auto leaf = std::make_unique<LeafT>(openvdb::Coord(ox, oy, 0), background, false);
            for (int y = 0; y < TILE; ++y) {
                for (int x = 0; x < TILE; ++x) {
                    const int n = x + TILE * y;
                    const float v = tiles[t]->value[size_t(n)];
                    const float outside = v < 0.0f ? -background : background;
                    for (int z = 0; z < TILE; ++z)
                        leaf->setValueOnly(openvdb::Coord(ox + x, oy + y, z), outside);
                    if ((tiles[t]->active >> n) & 1u) {
                        leaf->setValueOn(openvdb::Coord(ox + x, oy + y, 0),
                                         float(double(v) * voxel));
                    }
                }
            }
            leaves[t] = leaf.release();
        });
        for (LeafT* leaf : leaves)
            if (leaf) grid->tree().addLeaf(leaf);
        openvdb::tools::signedFloodFill(grid->tree(), mThreaded);
        return grid;
    }

private:
    std::unique_ptr<TileResult> computeTile(int ox, int oy, double halfWidth) const
    {
        const Vec<2> centre(ox + 0.5 * (TILE - 1), oy + 0.5 * (TILE - 1));
        double dc2 = std::numeric_limits<double>::max();
        for (size_t s = 0; s < mSegments.size(); ++s)
            dc2 = std::min(dc2, mSegments.distanceSqr(s, centre));
        const double dc = std::sqrt(dc2);
        if (std::isfinite(halfWidth) && dc - TILE_RADIUS > halfWidth) return nullptr;
        // Any node's nearest segment lies within dc + 2 R of the centre.
        const double reach = dc + 2.0 * TILE_RADIUS + 1e-9;
        std::vector<size_t> candidates;
        for (size_t s = 0; s < mSegments.size(); ++s)
            if (mSegments.distanceSqr(s, centre) <= reach * reach) candidates.push_back(s);
        auto result = std::make_unique<TileResult>();
        for (int y = 0; y < TILE; ++y) {
            for (int x = 0; x < TILE; ++x) {
                const Vec<2> p(ox + x, oy + y);
                double d2 = std::numeric_limits<double>::max();
                for (const size_t s : candidates)
                    d2 = std::min(d2, mSegments.distanceSqr(s, p));
                const double d = std::sqrt(d2);
                const int n = x + TILE * y;
                const bool inside = mCrossings.isInside(ox + x, oy + y);
                result->value[size_t(n)] = float(inside ? -d : d);
                if (!(d <= halfWidth)) continue;
                result->active |= uint64_t(1) << n;
            }
        }
        if (std::isfinite(halfWidth) && result->active == 0) return nullptr;
        return result;
    }

    const Segments2D& mSegments;
    RowCrossings mCrossings;
    bool mThreaded;
};

/// The segments of a curve with its points mapped by f (to index space).
template <typename F>
Segments2D
toSegments(const Surface<2>& s, F&& f)
{
    Segments2D out;
    out.a.reserve(s.elements.size());
    out.b.reserve(s.elements.size());
    for (const auto& e : s.elements) {
        out.a.push_back(f(s.points[size_t(e[0])]));
        out.b.push_back(f(s.points[size_t(e[1])]));
    }
    return out;
}

/// Tile range covering [lo, hi] (index units) on one axis.
void
tileRange(double lo, double hi, int& t0, int& t1)
{
    t0 = floorDiv(int(std::floor(lo)), TILE);
    t1 = floorDiv(int(std::ceil(hi)), TILE);
}

openvdb::FloatGrid::Ptr
band2D(const Segments2D& segs, double halfWidth, double voxel,
       const openvdb::math::Transform::Ptr& xform, bool threaded)
{
    double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
    double hi[2] = {-lo[0], -lo[1]};
    for (size_t s = 0; s < segs.size(); ++s) {
        for (int a = 0; a < 2; ++a) {
            lo[a] = std::min({lo[a], segs.a[s][a], segs.b[s][a]});
            hi[a] = std::max({hi[a], segs.a[s][a], segs.b[s][a]});
        }
    }
    int tx0, tx1, ty0, ty1;
    tileRange(lo[0] - halfWidth, hi[0] + halfWidth, tx0, tx1);
    tileRange(lo[1] - halfWidth, hi[1] + halfWidth, ty0, ty1);
    const TileRasterizer raster(segs, threaded);
    return raster.build(tx0, tx1, ty0, ty1, halfWidth, voxel, halfWidth * voxel, xform);
}

////////////////////////////////////////////////////////////////////////////////
// 3D: meshToVolume in the index space of the level

struct IndexMesh
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
};

IndexMesh
toIndexMesh(const Surface<3>& s, double invH)
{
    IndexMesh m;
    m.points.reserve(s.points.size());
    for (const Vec<3>& p : s.points)
        m.points.emplace_back(float(p[0] * invH), float(p[1] * invH), float(p[2] * invH));
    m.triangles.reserve(s.elements.size());
    for (const auto& t : s.elements)
        m.triangles.emplace_back(uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2]));
    return m;
}

/// Slots of exactBand's table of the triangles evaluated for a voxel (a power of two).
constexpr size_t VISIT_TABLE_SIZE = 256;

/// Bound on the steps of the descent over the mesh in exactBand (the start is the nearest of the
/// polygons meshToVolume found for the voxel and its neighbours, a few triangles from the
/// nearest one).
constexpr int MAX_DESCENT_STEPS = 64;

/// Replaces every active value of a meshToVolume band by the exact distance to the triangles
/// (keeping its sign, clamped to the background): the nearest of the closest polygons recorded
/// for the voxel and its 26 neighbours, improved by steepest descent over triangles sharing a
/// vertex. meshToVolume's own values are only approximate a few voxels from the surface
/// (measured errors up to 0.43 voxel at 3-4 voxels on a sphere).
void
exactBand(openvdb::FloatGrid& grid, const openvdb::Int32Grid& polygonIndex, const IndexMesh& m,
          double h, bool threaded)
{
    const size_t numTriangles = m.triangles.size();
    std::vector<openvdb::Vec3d> corners(numTriangles * 3);
    std::vector<uint32_t> begin(m.points.size() + 1, 0);
    for (size_t t = 0; t < numTriangles; ++t) {
        for (int c = 0; c < 3; ++c) {
            corners[t * 3 + size_t(c)] = openvdb::Vec3d(m.points[m.triangles[t][c]]);
            ++begin[m.triangles[t][c] + 1];
        }
    }
    for (size_t v = 0; v < m.points.size(); ++v)
        begin[v + 1] += begin[v];
    std::vector<int32_t> around(begin.back());
    {
        std::vector<uint32_t> next(begin.begin(), begin.end() - 1);
        for (size_t t = 0; t < numTriangles; ++t)
            for (int c = 0; c < 3; ++c)
                around[next[m.triangles[t][c]]++] = int32_t(t);
    }
    auto distanceSqr = [&](int32_t t, const openvdb::Vec3d& p) {
        const openvdb::Vec3d* c = &corners[size_t(t) * 3];
        return detail::triangleDistanceSqr(p, c[0], c[1], c[2]);
    };
    const double background = double(grid.background());
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(grid.tree());
    detail::forEachIndex(leaves.leafCount(), threaded, [&](size_t l) {
        auto index = polygonIndex.getConstAccessor();
        // Triangles already evaluated for this voxel, in a direct-mapped table (a collision only
        // evaluates a triangle again). That never changes the result: a triangle evaluated again
        // gives the same distance, which cannot beat (or tie with a lower index) the best one
        // that its first evaluation left. Entries of earlier voxels are told apart by the voxel
        // counter.
        struct Visit
        {
            int32_t triangle = -1;
            uint32_t voxel = 0;
        };
        std::array<Visit, VISIT_TABLE_SIZE> visits{};
        uint32_t voxel = 0;
        auto firstVisit = [&visits, &voxel](int32_t t) {
            Visit& v = visits[size_t(t) & (VISIT_TABLE_SIZE - 1)];
            if (v.voxel == voxel && v.triangle == t) return false;
            v.triangle = t;
            v.voxel = voxel;
            return true;
        };
        for (auto it = leaves.leaf(l).beginValueOn(); it; ++it) {
            const openvdb::Coord ijk = it.getCoord();
            const openvdb::Vec3d p = ijk.asVec3d();
            ++voxel;
            double best = std::numeric_limits<double>::max();
            int32_t bestT = -1;
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int32_t t = index.getValue(ijk.offsetBy(dx, dy, dz));
                        if (t < 0 || size_t(t) >= numTriangles || !firstVisit(t)) continue;
                        const double d = distanceSqr(t, p);
                        if (d < best || (d == best && t < bestT)) {
                            best = d;
                            bestT = t;
                        }
                    }
            if (bestT < 0) continue; // no polygon recorded: keep meshToVolume's value
            for (int step = 0; step < MAX_DESCENT_STEPS; ++step) {
                const int32_t current = bestT;
                for (int c = 0; c < 3; ++c) {
                    const uint32_t v = m.triangles[size_t(current)][c];
                    for (uint32_t k = begin[v]; k < begin[v + 1]; ++k) {
                        const int32_t t = around[k];
                        if (!firstVisit(t)) continue;
                        const double d = distanceSqr(t, p);
                        if (d < best || (d == best && t < bestT)) {
                            best = d;
                            bestT = t;
                        }
                    }
                }
                if (bestT == current) break;
            }
            const double magnitude = std::min(std::sqrt(best) * h, background);
            it.setValue(float(*it < 0.0f ? -magnitude : magnitude));
        }
    });
}

openvdb::FloatGrid::Ptr
meshBand(const IndexMesh& m, const openvdb::math::Transform::Ptr& xform, double exterior,
         double interior, bool threaded)
{
    const double h = xform->voxelSize()[0];
    const openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> adapter(
        m.points, m.triangles);
    openvdb::util::NullInterrupter interrupter;
    openvdb::Int32Grid polygonIndex;
    openvdb::FloatGrid::Ptr grid = openvdb::tools::meshToVolume<openvdb::FloatGrid>(
        interrupter, adapter, *xform, float(exterior), float(interior), MESH_TO_VOLUME_FLAGS,
        &polygonIndex);
    exactBand(*grid, polygonIndex, m, h, threaded);
    grid->setTransform(xform);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    return grid;
}

/// An upper bound (voxels) on the distance from any node of [lo, hi]^3 to the surface: the
/// largest distance from sample nodes BOUND_SAMPLE_SPACING apart to a subset of the vertices,
/// plus the distance from any node to its nearest sample.
double
boxDistanceBound(const IndexMesh& m, int lo, int hi, bool threaded)
{
    std::vector<int> axis;
    for (int i = lo; i < hi; i += BOUND_SAMPLE_SPACING)
        axis.push_back(i);
    axis.push_back(hi);
    const size_t n = axis.size();
    const size_t stride = std::max<size_t>(1, m.points.size() / BOUND_MAX_VERTICES);
    std::vector<double> best(n * n * n);
    detail::forEachIndex(best.size(), threaded, [&](size_t s) {
        const openvdb::Vec3d p(axis[s % n], axis[(s / n) % n], axis[s / (n * n)]);
        double d2 = std::numeric_limits<double>::max();
        for (size_t v = 0; v < m.points.size(); v += stride)
            d2 = std::min(d2, (openvdb::Vec3d(m.points[v]) - p).lengthSqr());
        best[s] = std::sqrt(d2);
    });
    const double farthest = *std::max_element(best.begin(), best.end());
    return farthest + 0.5 * std::sqrt(3.0) * BOUND_SAMPLE_SPACING + 1.0;
}

} // namespace

template <>
openvdb::FloatGrid::Ptr
distanceBand<3>(const Surface<3>& surface, int level, double halfWidthVoxels, bool threaded)
{
    validate("distanceBand", level, halfWidthVoxels);
    checkSurface(surface, "distanceBand");
    const double h = std::ldexp(1.0, -level);
    return meshBand(toIndexMesh(surface, 1.0 / h),
                    openvdb::math::Transform::createLinearTransform(h), halfWidthVoxels,
                    halfWidthVoxels, threaded);
}

template <>
openvdb::FloatGrid::Ptr
distanceBand<2>(const Surface<2>& surface, int level, double halfWidthVoxels, bool threaded)
{
    validate("distanceBand", level, halfWidthVoxels);
    checkSurface(surface, "distanceBand");
    const double h = std::ldexp(1.0, -level);
    const Segments2D segs = toSegments(surface, [h](const Vec<2>& p) { return Vec<2>(p / h); });
    return band2D(segs, halfWidthVoxels, h, openvdb::math::Transform::createLinearTransform(h),
                  threaded);
}

template <>
openvdb::FloatGrid::Ptr
distanceBox<3>(const Surface<3>& surface, int level, int padding, bool threaded)
{
    validate("distanceBox", level, MIN_DISTANCE_HALF_WIDTH_VOXELS);
    if (padding < 0) OPENVDB_THROW(openvdb::ValueError, "distanceBox: padding must be >= 0");
    checkSurface(surface, "distanceBox");
    const double h = std::ldexp(1.0, -level);
    const IndexMesh mesh = toIndexMesh(surface, 1.0 / h);
    const double bound =
        std::max(MIN_DISTANCE_HALF_WIDTH_VOXELS,
                 boxDistanceBound(mesh, -padding, (1 << level) + padding, threaded));
    openvdb::FloatGrid::Ptr grid =
        meshBand(mesh, openvdb::math::Transform::createLinearTransform(h), bound, bound, threaded);
    if (!coversUnitBoxNodes(*grid, level, padding)) {
        OPENVDB_THROW(openvdb::RuntimeError,
                      "distanceBox: internal error: the band does not cover the node box");
    }
    return grid;
}

template <>
openvdb::FloatGrid::Ptr
distanceBox<2>(const Surface<2>& surface, int level, int padding, bool threaded)
{
    validate("distanceBox", level, MIN_DISTANCE_HALF_WIDTH_VOXELS);
    if (padding < 0) OPENVDB_THROW(openvdb::ValueError, "distanceBox: padding must be >= 0");
    checkSurface(surface, "distanceBox");
    const double h = std::ldexp(1.0, -level);
    const Segments2D segs = toSegments(surface, [h](const Vec<2>& p) { return Vec<2>(p / h); });
    const int n = 1 << level;
    int t0, t1;
    tileRange(-padding, n + padding, t0, t1);
    const TileRasterizer raster(segs, threaded);
    return raster.build(t0, t1, t0, t1, std::numeric_limits<double>::infinity(), h,
                        MIN_DISTANCE_HALF_WIDTH_VOXELS * h,
                        openvdb::math::Transform::createLinearTransform(h));
}

template <int D>
typename FieldSampler<D>::ConstPtr
buildShapeSampler(const Surface<D>& surface, int level, const ShapeSamplerOptions& opts,
                  ShapeSamplerCache<D>& cache)
{
    const int dense = D == 3 ? opts.denseLevel3D : opts.denseLevel2D;
    if (dense < MIN_DISTANCE_LEVEL) {
        OPENVDB_THROW(openvdb::ValueError, "buildShapeSampler: dense level must be >= " +
                                               std::to_string(MIN_DISTANCE_LEVEL));
    }
    validate("buildShapeSampler", level, opts.bandHalfWidthVoxels);
    if (!cache.claim(&surface)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "buildShapeSampler: the cache holds the tiers of another surface");
    }
    cache.dropBelow(level);
    ShapeFieldOptions fields = opts.fields;
    fields.threaded = fields.threaded && opts.threaded;
    // One sampler per tier, so that later levels can share it.
    auto single = [&](openvdb::FloatGrid::ConstPtr grid) {
        return std::make_shared<const FieldSampler<D>>(
            std::vector<openvdb::FloatGrid::ConstPtr>{grid}, fields);
    };
    auto band = [&](int l) {
        return cache.tier('b', l, [&] {
            return single(distanceBand<D>(surface, l, opts.bandHalfWidthVoxels, opts.threaded));
        });
    };
    std::vector<typename FieldSampler<D>::ConstPtr> tiers;
    // At or below the dense level the box tier alone is as fine as a band would be.
    if (level > dense) {
        tiers.push_back(band(level));
        if (level - 2 > dense) tiers.push_back(band(level - 2));
    }
    const int boxLevel = std::min(level, dense);
    tiers.push_back(cache.tier('x', boxLevel, [&] {
        return single(distanceBox<D>(surface, boxLevel, SAMPLER_BOX_PADDING, opts.threaded));
    }));
    return std::make_shared<const FieldSampler<D>>(tiers);
}

template <int D>
typename FieldSampler<D>::ConstPtr
buildShapeSampler(const Surface<D>& surface, int level, const ShapeSamplerOptions& opts)
{
    ShapeSamplerCache<D> cache;
    return buildShapeSampler(surface, level, opts, cache);
}

template <>
openvdb::FloatGrid::Ptr
levelSetFromSurface<3>(const Surface<3>& worldSurface, const openvdb::math::Transform& xform,
                       double halfWidthVoxels)
{
    validate("levelSetFromSurface", MIN_DISTANCE_LEVEL, halfWidthVoxels);
    checkSurface(worldSurface, "levelSetFromSurface");
    const openvdb::Vec3d voxel = xform.voxelSize();
    if (!xform.isLinear() || !(voxel[0] > 0.0) || std::abs(voxel[1] - voxel[0]) > 1e-9 * voxel[0] ||
        std::abs(voxel[2] - voxel[0]) > 1e-9 * voxel[0]) {
        OPENVDB_THROW(openvdb::ValueError,
                      "levelSetFromSurface: the transform must be linear with uniform voxels");
    }
    IndexMesh mesh;
    mesh.points.reserve(worldSurface.points.size());
    for (const Vec<3>& p : worldSurface.points)
        mesh.points.emplace_back(xform.worldToIndex(openvdb::Vec3d(p[0], p[1], p[2])));
    mesh.triangles.reserve(worldSurface.elements.size());
    for (const auto& t : worldSurface.elements)
        mesh.triangles.emplace_back(uint32_t(t[0]), uint32_t(t[1]), uint32_t(t[2]));
    return meshBand(mesh, xform.copy(), halfWidthVoxels, halfWidthVoxels, /*threaded=*/true);
}

template <>
openvdb::FloatGrid::Ptr
levelSetFromSurface<2>(const Surface<2>& worldSurface, const openvdb::math::Transform& xform,
                       double halfWidthVoxels)
{
    validate("levelSetFromSurface", MIN_DISTANCE_LEVEL, halfWidthVoxels);
    checkSurface(worldSurface, "levelSetFromSurface");
    // A uniform scale plus a translation: index axis a maps to world axis a times the voxel.
    const double voxel = xform.voxelSize()[0];
    bool ok = xform.isLinear() && voxel > 0.0;
    const openvdb::Vec3d origin = xform.indexToWorld(openvdb::Vec3d(0.0));
    for (int a = 0; a < 3 && ok; ++a) {
        openvdb::Vec3d e(0.0), expected(0.0);
        e[a] = 1.0;
        expected[a] = voxel;
        ok = (xform.indexToWorld(e) - origin - expected).length() <= 1e-9 * voxel;
    }
    if (!ok) {
        OPENVDB_THROW(openvdb::ValueError, "levelSetFromSurface: a 2D slice needs a transform "
                                           "that is a uniform scale plus a translation");
    }
    const Segments2D segs = toSegments(worldSurface, [&xform](const Vec<2>& p) {
        const openvdb::Vec3d i = xform.worldToIndex(openvdb::Vec3d(p[0], p[1], 0.0));
        return Vec<2>(i[0], i[1]);
    });
    return band2D(segs, halfWidthVoxels, voxel, xform.copy(), /*threaded=*/true);
}

template FieldSampler<2>::ConstPtr buildShapeSampler<2>(const Surface<2>&, int,
                                                        const ShapeSamplerOptions&);
template FieldSampler<3>::ConstPtr buildShapeSampler<3>(const Surface<3>&, int,
                                                        const ShapeSamplerOptions&);
template FieldSampler<2>::ConstPtr
buildShapeSampler<2>(const Surface<2>&, int, const ShapeSamplerOptions&, ShapeSamplerCache<2>&);
template FieldSampler<3>::ConstPtr
buildShapeSampler<3>(const Surface<3>&, int, const ShapeSamplerOptions&, ShapeSamplerCache<3>&);

} // namespace vdbmatch
