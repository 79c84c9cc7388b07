/// @file InverseGrid.cc
#include "InverseGrid.h"

#include <vdbmatch/io/DeformationIO.h>

#include <openvdb/thread/Threading.h>
#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <vector>

namespace vdbmatch {

InverseGridResult
makeInverseGrid(const DeformationField& phi, bool threaded,
                openvdb::util::NullInterrupter* interrupter)
{
    using TreeT = openvdb::Vec3STree;
    InverseGridResult result;
    openvdb::Vec3SGrid::Ptr grid = phi.grid().deepCopy();
    openvdb::tree::LeafManager<TreeT> leaves(grid->tree());
    const openvdb::math::Transform& xform = grid->transform();
    const std::size_t count = leaves.leafCount();
    std::vector<std::size_t> nodes(count, 0), failures(count, 0);
    std::vector<double> residual(count, 0.0);
    std::atomic<bool> stopped{false};
    auto body = [&](const tbb::blocked_range<std::size_t>& range) {
        DeformationField::Cursor cursor(phi);
        for (std::size_t li = range.begin(); li != range.end(); ++li) {
            if (stopped.load(std::memory_order_relaxed)) return;
            if (interrupter && interrupter->wasInterrupted()) {
                stopped = true;
                if (threaded) openvdb::thread::cancelGroupExecution();
                return;
            }
            auto& leaf = leaves.leaf(li);
            bool haveGuess = false;
            openvdb::Vec3d previous(0.0); // phi^{-1}(y) - y of the previous node of this leaf
            for (auto v = leaf.beginValueOn(); v; ++v) {
                const openvdb::Vec3d y = xform.indexToWorld(v.getCoord());
                const DeformationField::InverseResult r =
                    haveGuess ? cursor.inverse(y, y + previous) : cursor.inverse(y);
                previous = r.x - y;
                haveGuess = true;
                ++nodes[li];
                if (!r.found) ++failures[li];
                residual[li] = std::max(residual[li], r.residual);
                v.setValue(openvdb::Vec3s(previous));
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
    for (std::size_t li = 0; li < count; ++li) {
        result.nodes += nodes[li];
        result.failures += failures[li];
        result.maxResidual = std::max(result.maxResidual, residual[li]);
    }
    grid->setName(DEFORMATION_GRID_NAME);
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    grid->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    grid->setIsInWorldSpace(true);
    // The inverse of an inverse is a forward map.
    bool wasInverse = false;
    if (auto m = phi.grid().getMetadata<openvdb::BoolMetadata>(INVERSE_METADATA)) {
        wasInverse = m->value();
    }
    grid->removeMeta(INVERSE_METADATA);
    grid->insertMeta(INVERSE_METADATA, openvdb::BoolMetadata(!wasInverse));
    result.grid = grid;
    return result;
}

} // namespace vdbmatch
