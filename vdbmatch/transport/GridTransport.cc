/// @file GridTransport.cc
/// @brief A level set carried as its surface, a field pulled back through the map.
#include "GridTransport.h"

#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/SurfaceExtraction.h>

#include <openvdb/thread/Threading.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/Morphology.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

namespace vdbmatch {

namespace {

/// Throws unless the grid's transform is linear with uniform voxels.
void
checkTransform(const openvdb::GridBase& grid)
{
    const openvdb::math::Transform& xform = grid.transform();
    const openvdb::Vec3d v = xform.voxelSize();
    const bool uniform =
        std::abs(v[0] - v[1]) <= 1e-6 * v[0] && std::abs(v[0] - v[2]) <= 1e-6 * v[0];
    if (!xform.isLinear() || !uniform || !(v[0] > 0)) {
        OPENVDB_THROW(openvdb::ValueError, "grid '" << grid.getName()
                                                    << "': the transform is not linear with "
                                                       "uniform voxels");
    }
}

/// Moves the points of @a surface by phi or phi^{-1}; returns the number of failed walks.
template <int D>
std::size_t
moveSurface(Surface<D>& surface, const DeformationField& phi, bool inverse, bool threaded, double z)
{
    std::vector<openvdb::Vec3d> points(surface.points.size());
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (int a = 0; a < D; ++a)
            points[i][a] = surface.points[i][a];
        if (D == 2) points[i][2] = z;
    }
    const std::size_t failures = phi.mapPoints(points, inverse, threaded);
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (int a = 0; a < D; ++a)
            surface.points[i][a] = points[i][a];
    }
    return failures;
}

/// Copies the metadata of @a from that the rebuilt grid does not set itself.
void
copyMetadata(const openvdb::GridBase& from, openvdb::GridBase& to)
{
    for (auto it = from.beginMeta(); it != from.endMeta(); ++it) {
        const std::string& name = it->first;
        if (name.rfind("file_", 0) == 0) continue; // statistics, rewritten by the writer
        if (to[name]) continue;
        to.insertMeta(name, *it->second);
    }
}

GridTransportResult
transportLevelSet(const openvdb::FloatGrid& in, const DeformationField& phi, bool inverse,
                  bool threaded)
{
    GridTransportResult result;
    result.levelSet = true;
    const double voxel = in.voxelSize()[0];
    const double halfWidth =
        std::max(MIN_DISTANCE_HALF_WIDTH_VOXELS, double(in.background()) / voxel);
    openvdb::FloatGrid::Ptr out;
    if (isSlice(in)) {
        if (phi.dimension() != 2) {
            OPENVDB_THROW(openvdb::ValueError,
                          "grid '" << in.getName()
                                   << "' is a 2D slice but the deformation is 3D; carry it with "
                                      "a 2D deformation");
        }
        const int k0 = in.tree().beginValueOn().getCoord().z();
        Surface<2> curve = extractCurve(in);
        const double z = in.transform().indexToWorld(openvdb::Vec3d(0.0, 0.0, k0))[2];
        result.inverseFailures = moveSurface(curve, phi, inverse, threaded, z);
        result.points = curve.points.size();
        openvdb::math::Transform::Ptr xform = in.transform().copy();
        xform->preTranslate(openvdb::Vec3d(0.0, 0.0, double(k0)));
        out = levelSetFromSurface<2>(curve, *xform, halfWidth);
    } else {
        Surface<3> surface = extractSurface(in);
        result.inverseFailures = moveSurface(surface, phi, inverse, threaded, 0.0);
        result.points = surface.points.size();
        out = levelSetFromSurface<3>(surface, in.transform(), halfWidth);
    }
    out->setName(in.getName());
    out->setGridClass(openvdb::GRID_LEVEL_SET);
    copyMetadata(in, *out);
    result.grid = out;
    return result;
}

/// g(y) = f(phi^{-1}(y)) (forward) or f(phi(y)) (inverse) on the image of f's active voxels.
template <typename GridT>
GridTransportResult
pullBack(const GridT& in, const DeformationField& phi, bool inverse, bool threaded,
         openvdb::util::NullInterrupter* interrupter)
{
    using TreeT = typename GridT::TreeType;
    using ValueT = typename GridT::ValueType;
    GridTransportResult result;
    const openvdb::math::Transform& xform = in.transform();

    // The images of the active voxel centres (tiles voxelised) give the output's topology.
    openvdb::MaskGrid::Ptr support = openvdb::MaskGrid::create();
    support->tree().topologyUnion(in.tree());
    support->tree().voxelizeActiveTiles();
    std::vector<openvdb::Vec3d> centres;
    centres.reserve(support->activeVoxelCount());
    for (auto v = support->tree().cbeginValueOn(); v; ++v)
        centres.push_back(xform.indexToWorld(v.getCoord()));
    // The images of the voxel centres: phi forward, phi^{-1} for the inverse.
    result.inverseFailures += phi.mapPoints(centres, inverse, threaded);
    if (interrupter && interrupter->wasInterrupted()) return result;
    openvdb::MaskGrid::Ptr image = openvdb::MaskGrid::create();
    {
        auto acc = image->getAccessor();
        for (const openvdb::Vec3d& y : centres) {
            const openvdb::Vec3d p = xform.worldToIndex(y);
            acc.setValueOn(openvdb::Coord::round(p));
        }
    }
    centres = std::vector<openvdb::Vec3d>();
    openvdb::tools::dilateActiveValues(image->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);

    typename GridT::Ptr out = in.copyWithNewTree();
    out->tree().topologyUnion(image->tree());
    image.reset();
    openvdb::tree::LeafManager<TreeT> leaves(out->tree());
    const std::size_t count = leaves.leafCount();
    std::vector<std::size_t> failures(count, 0), evaluated(count, 0);
    std::atomic<bool> stopped{false};
    auto body = [&](const tbb::blocked_range<std::size_t>& range) {
        typename GridT::ConstAccessor source = in.getConstAccessor();
        DeformationField::Cursor map(phi);
        for (std::size_t li = range.begin(); li != range.end(); ++li) {
            if (stopped.load(std::memory_order_relaxed)) return;
            if (interrupter && interrupter->wasInterrupted()) {
                stopped = true;
                if (threaded) openvdb::thread::cancelGroupExecution();
                return;
            }
            auto& leaf = leaves.leaf(li);
            bool haveGuess = false;
            openvdb::Vec3d offset(0.0); // phi^{-1}(y) - y of the previous voxel of this leaf
            for (auto v = leaf.beginValueOn(); v; ++v) {
                const openvdb::Vec3d y = xform.indexToWorld(v.getCoord());
                openvdb::Vec3d x;
                if (inverse) {
                    x = map.apply(y);
                } else {
                    const DeformationField::InverseResult r =
                        haveGuess ? map.inverse(y, y + offset) : map.inverse(y);
                    if (!r.found) ++failures[li];
                    x = r.x;
                    offset = x - y;
                    haveGuess = true;
                }
                ++evaluated[li];
                const openvdb::Vec3d p = xform.worldToIndex(x);
                // Keep the voxel if the trilinear stencil touches an active input voxel.
                const openvdb::Coord base = openvdb::Coord::floor(p);
                bool touches = false;
                for (int c = 0; c < 8 && !touches; ++c) {
                    touches = source.isValueOn(base.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1));
                }
                if (!touches) {
                    v.setValue(in.background());
                    v.setValueOff();
                    continue;
                }
                ValueT value;
                openvdb::tools::BoxSampler::sample(source, p, value);
                v.setValue(value);
            }
        }
    };
    const tbb::blocked_range<std::size_t> all(0, count, 1);
    if (threaded) {
        tbb::parallel_for(all, body);
    } else {
        body(all);
    }
    if (stopped) return result;
    openvdb::tools::pruneInactive(out->tree(), threaded);
    for (std::size_t li = 0; li < count; ++li) {
        result.inverseFailures += failures[li];
        result.points += evaluated[li];
    }
    result.grid = out;
    return result;
}

} // namespace

bool
isTransportableGrid(const openvdb::GridBase& grid)
{
    return grid.isType<openvdb::FloatGrid>() || grid.isType<openvdb::DoubleGrid>() ||
           grid.isType<openvdb::Vec3SGrid>() || grid.isType<openvdb::Vec3DGrid>();
}

GridTransportResult
transportGrid(const openvdb::GridBase& grid, const DeformationField& phi, bool inverse,
              bool threaded, openvdb::util::NullInterrupter* interrupter)
{
    if (!isTransportableGrid(grid)) {
        OPENVDB_THROW(openvdb::TypeError, "grid '" << grid.getName() << "' of type "
                                                   << grid.valueType()
                                                   << " cannot be carried (supported: float, "
                                                      "double, vec3s and vec3d grids)");
    }
    checkTransform(grid);
    if (phi.dimension() == 2) {
        const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
        if (box.min().z() != box.max().z()) {
            OPENVDB_THROW(openvdb::ValueError,
                          "grid '" << grid.getName()
                                   << "' is 3D but the deformation is 2D; a 2D deformation "
                                      "carries one-layer (slice) grids");
        }
    }
    if (const auto* fog = dynamic_cast<const openvdb::FloatGrid*>(&grid)) {
        if (grid.getGridClass() == openvdb::GRID_LEVEL_SET) {
            return transportLevelSet(*fog, phi, inverse, threaded);
        }
        return pullBack(*fog, phi, inverse, threaded, interrupter);
    }
    if (const auto* g = dynamic_cast<const openvdb::DoubleGrid*>(&grid)) {
        return pullBack(*g, phi, inverse, threaded, interrupter);
    }
    if (const auto* g = dynamic_cast<const openvdb::Vec3SGrid*>(&grid)) {
        return pullBack(*g, phi, inverse, threaded, interrupter);
    }
    return pullBack(static_cast<const openvdb::Vec3DGrid&>(grid), phi, inverse, threaded,
                    interrupter);
}

} // namespace vdbmatch
