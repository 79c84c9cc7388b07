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
            // The previous node of this leaf: y, phi^{-1}(y) and D phi^{-1} there. The guess
            // for the next node is first-order (exact where phi is affine), so that the walk
            // mostly starts in its last simplex (1.2 simplices per node on the starfish pair
            // instead of 2.2 from phi^{-1}(y') ~ y' + phi^{-1}(y) - y).
            bool haveGuess = false;
            DeformationField::InverseResult previous;
            openvdb::Vec3d previousY(0.0);
            for (auto v = leaf.beginValueOn(); v; ++v) {
                const openvdb::Vec3d y = xform.indexToWorld(v.getCoord());
                const DeformationField::InverseResult r =
                    haveGuess ? cursor.inverse(y, previous.x + previous.jacobian * (y - previousY))
                              : cursor.inverse(y);
                previous = r;
                previousY = y;
                haveGuess = true;
                ++nodes[li];
                if (!r.found) ++failures[li];
                residual[li] = std::max(residual[li], r.residual);
                v.setValue(openvdb::Vec3s(r.x - y));
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
