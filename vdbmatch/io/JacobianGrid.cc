/// @file JacobianGrid.cc
#include "JacobianGrid.h"

#include <openvdb/Exceptions.h>
#include <openvdb/thread/Threading.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace vdbmatch {

openvdb::FloatGrid::Ptr
makeJacobianGrid(const DeformationField& phi, bool logarithm, bool threaded,
                 openvdb::util::NullInterrupter* interrupter)
{
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const int dim = phi.dimension();
    openvdb::CoordBBox box;
    phi.grid().tree().evalActiveVoxelBoundingBox(box);
    // Cells: lowest corners box.min() .. box.max() - 1 on the axes of the dimension.
    openvdb::Coord lo = box.min(), hi = box.max();
    for (int a = 0; a < dim; ++a)
        hi[a] -= 1;
    const float background = logarithm ? 0.0f : 1.0f;
    auto grid = openvdb::FloatGrid::create(background);
    if (hi[0] >= lo[0] && hi[1] >= lo[1] && hi[2] >= lo[2]) {
        // One task per leaf-sized block of cells; leaves are added in a fixed order.
        const int S = int(LeafT::DIM);
        auto blocks = [&](int a) { return (hi[a] - lo[a]) / S + 1; };
        const int bx = blocks(0), by = blocks(1), bz = dim == 3 ? blocks(2) : 1;
        const std::size_t count = std::size_t(bx) * std::size_t(by) * std::size_t(bz);
        std::vector<std::unique_ptr<LeafT>> leaves(count);
        std::vector<double> mins(count, std::numeric_limits<double>::infinity());
        std::vector<double> maxs(count, -std::numeric_limits<double>::infinity());
        std::vector<char> folded(count, 0);
        std::atomic<bool> stopped{false};
        const double invVoxel = 1.0 / phi.voxelSize();
        auto body = [&](const tbb::blocked_range<std::size_t>& range) {
            openvdb::tree::ValueAccessor<const openvdb::Vec3STree, false> acc(phi.grid().tree());
            std::vector<openvdb::Vec3d> corners(std::size_t((S + 1) * (S + 1) * (S + 1)));
            for (std::size_t b = range.begin(); b != range.end(); ++b) {
                if (stopped.load(std::memory_order_relaxed)) return;
                if (interrupter && interrupter->wasInterrupted()) {
                    stopped = true;
                    if (threaded) openvdb::thread::cancelGroupExecution();
                    return;
                }
                const openvdb::Coord start(lo[0] + S * int(b % std::size_t(bx)),
                                           lo[1] + S * int((b / std::size_t(bx)) % std::size_t(by)),
                                           lo[2] +
                                               S * int(b / (std::size_t(bx) * std::size_t(by))));
                auto leaf = std::make_unique<LeafT>(start, background, false);
                double dets[6];
                const openvdb::Coord end(std::min(hi[0], start[0] + S - 1),
                                         std::min(hi[1], start[1] + S - 1),
                                         dim == 3 ? std::min(hi[2], start[2] + S - 1) : lo[2]);
                // The block's corner displacements, read once (index units): (S+1)^d nodes
                // instead of 2^d look-ups per cell.
                const int kz = dim == 3 ? S + 1 : 1;
                for (int k = 0; k < kz; ++k)
                    for (int j = 0; j <= S; ++j)
                        for (int i = 0; i <= S; ++i) {
                            openvdb::Coord v = start.offsetBy(i, j, k);
                            if (dim == 2) v[2] = phi.sliceIndex();
                            corners[std::size_t(i + (S + 1) * (j + (S + 1) * k))] =
                                openvdb::Vec3d(acc.getValue(v)) * invVoxel;
                        }
                openvdb::Vec3d u[8];
                for (int k = start[2]; k <= end[2]; ++k) {
                    for (int j = start[1]; j <= end[1]; ++j) {
                        for (int i = start[0]; i <= end[0]; ++i) {
                            const openvdb::Coord c(i, j, k);
                            const int li = i - start[0], lj = j - start[1], lk = k - start[2];
                            for (int q = 0; q < (1 << dim); ++q)
                                u[q] = corners[std::size_t(
                                    (li + (q & 1)) +
                                    (S + 1) * ((lj + ((q >> 1) & 1)) + (S + 1) * (lk + (q >> 2))))];
                            const int n = DeformationField::cellDeterminants(dim, u, dets);
                            double mean = 0;
                            for (int s = 0; s < n; ++s) {
                                mean += dets[s];
                                mins[b] = std::min(mins[b], dets[s]);
                                maxs[b] = std::max(maxs[b], dets[s]);
                            }
                            mean /= n;
                            if (logarithm && !(mean > 0)) folded[b] = 1;
                            leaf->setValueOn(
                                c, float(logarithm ? std::log(std::max(mean, 1e-300)) : mean));
                        }
                    }
                }
                leaves[b] = std::move(leaf);
            }
        };
        const tbb::blocked_range<std::size_t> all(0, count, 1);
        if (threaded) {
            tbb::parallel_for(all, body);
        } else {
            body(all);
        }
        if (stopped) return nullptr;
        double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
        for (std::size_t b = 0; b < count; ++b) {
            if (folded[b]) {
                OPENVDB_THROW(openvdb::ValueError,
                              "makeJacobianGrid: log det D phi is undefined: phi folds (a cell's "
                              "volume ratio is not positive)");
            }
            lowest = std::min(lowest, mins[b]);
            highest = std::max(highest, maxs[b]);
            grid->tree().addLeaf(leaves[b].release());
        }
        grid->insertMeta("vdbmatch_det_min", openvdb::DoubleMetadata(lowest));
        grid->insertMeta("vdbmatch_det_max", openvdb::DoubleMetadata(highest));
    }
    auto xform = phi.grid().transform().copy();
    const double half = 0.5 * phi.voxelSize();
    xform->postTranslate(openvdb::Vec3d(half, half, dim == 3 ? half : 0.0));
    grid->setTransform(xform);
    grid->setName(logarithm ? LOG_JACOBIAN_GRID_NAME : JACOBIAN_GRID_NAME);
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    return grid;
}

} // namespace vdbmatch
