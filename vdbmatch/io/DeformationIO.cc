/// @file DeformationIO.cc
#include "DeformationIO.h"

#include "VdbFileCheck.h"

#include <vdbmatch/multiscale/Prolongation.h>

#include <openvdb/Exceptions.h>
#include <openvdb/io/File.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace vdbmatch {

namespace {

/// World z of the plane of 2D shapes: the centre of the placed box (z = 1/2 in Omega).
double
planeWorldZ(const UnitBoxPlacement& placement)
{
    return placement.toWorld(openvdb::Vec3d(0.0, 0.0, 0.5)).z();
}

} // namespace

template <int D>
openvdb::Vec3SGrid::Ptr
makeDeformationGrid(const SimplexLattice<D>& lattice, const NodeVectors<D>& u,
                    const UnitBoxPlacement& placement, int outputLevel, bool threaded)
{
    using LeafT = openvdb::Vec3SGrid::TreeType::LeafNodeType;
    if (std::size_t(u.cols()) != lattice.nodeCount()) {
        OPENVDB_THROW(openvdb::ValueError, "makeDeformationGrid: expected " << lattice.nodeCount()
                                                                            << " node values, got "
                                                                            << u.cols());
    }
    const int level = outputLevel <= 0 ? lattice.level() : outputLevel;
    if (level > lattice.level() || level > 12) {
        OPENVDB_THROW(openvdb::ValueError, "makeDeformationGrid: output level "
                                               << level << " must be in [1, " << lattice.level()
                                               << "]");
    }
    const int n = 1 << level; // nodes 0..n per axis
    const double H = std::ldexp(1.0, -level);
    const double toWorld = 1.0 / placement.scale;

    using Interpolator = multiscale::PiecewiseLinearInterpolator<D>;
    using Cell = typename SimplexLattice<D>::Cell;
    const Interpolator phi(lattice);
    // Lattice index units per output voxel (the output level is at most the lattice's).
    const int scale = 1 << (lattice.level() - level);
    // The cell containing the whole box of a leaf's nodes, in the half-open sense (its nodes are
    // inside the cell or on its lower faces), or -1.
    auto leafCell = [&](typename Interpolator::Cursor& cursor, const openvdb::Coord& origin) {
        Vec<D> centre;
        for (int a = 0; a < D; ++a)
            centre[a] = std::min(1.0, (origin[a] + 0.5 * (LeafT::DIM - 1)) * H);
        const int32_t ci = cursor.cell(centre);
        if (ci < 0) return int32_t(-1);
        const Cell& c = lattice.cells()[std::size_t(ci)];
        const int side = 1 << c.log2Size;
        for (int a = 0; a < D; ++a) {
            const int first = origin[a] * scale, last = (origin[a] + int(LeafT::DIM) - 1) * scale;
            if (first < c.origin[a] || last >= c.origin[a] + side) return int32_t(-1);
        }
        return ci;
    };
    // For a leaf inside the cell, whether its nodes on the cell's lower face along axis a, and
    // on no other face of the cell, are located in the cell by the search as well: yes if no
    // cell across that face is finer (the search tries the finer sizes first, and at the cell's
    // own size the cell itself first). That holds if one cell, at least as large, contains the
    // layer across the leaf's face in the open sense, or if the face is the boundary of Omega.
    auto lowerFaceInCell = [&](typename Interpolator::Cursor& cursor, const Cell& c,
                               const openvdb::Coord& origin, int a) {
        if (c.origin[a] == 0) return true;
        // The leaf's nodes on that face, lattice index units: lo..hi along the other axes.
        std::array<int, D> lo, hi;
        Vec<D> probe;
        for (int b = 0; b < D; ++b) {
            lo[b] = std::max(origin[b] * scale, c.origin[b] + 1);
            hi[b] = std::min(origin[b] + int(LeafT::DIM) - 1, n) * scale;
            probe[b] = 0.5 * (lo[b] + hi[b]) / lattice.resolution();
        }
        probe[a] = (c.origin[a] - 0.5) / lattice.resolution();
        const int32_t across = cursor.cell(probe);
        if (across < 0) return false;
        const Cell& other = lattice.cells()[std::size_t(across)];
        if (other.log2Size < c.log2Size) return false;
        const int side = 1 << other.log2Size;
        for (int b = 0; b < D; ++b) {
            if (b == a) continue;
            if (!(other.origin[b] < lo[b] && hi[b] < other.origin[b] + side)) return false;
        }
        return true;
    };
    // The locations of the points of a cell, per cell size up to 32 lattice voxels (32^3
    // entries): the leaves inside one cell read them instead of locating every node.
    constexpr int MAX_TABLE_LOG2_SIZE = 5;
    std::vector<std::vector<typename Interpolator::Location>> tables(MAX_TABLE_LOG2_SIZE + 1);
    for (const Cell& c : lattice.cells())
        if (c.log2Size <= MAX_TABLE_LOG2_SIZE && tables[std::size_t(c.log2Size)].empty())
            tables[std::size_t(c.log2Size)] = Interpolator::cellTable(c.log2Size);
    const int leaves1 = (n + 1 + int(LeafT::DIM) - 1) / int(LeafT::DIM);
    const int leavesZ = D == 3 ? leaves1 : 1;
    const std::size_t leafCount =
        std::size_t(leaves1) * std::size_t(leaves1) * std::size_t(leavesZ);
    std::vector<std::unique_ptr<LeafT>> leaves(leafCount);
    std::vector<char> bad(leafCount, 0);

    auto fill = [&](const tbb::blocked_range<std::size_t>& range) {
        typename Interpolator::Cursor cursor(phi);
        for (std::size_t li = range.begin(); li != range.end(); ++li) {
            const int bx = int(li % std::size_t(leaves1));
            const int by = int((li / std::size_t(leaves1)) % std::size_t(leaves1));
            const int bz = int(li / (std::size_t(leaves1) * std::size_t(leaves1)));
            const openvdb::Coord origin(bx * int(LeafT::DIM), by * int(LeafT::DIM),
                                        bz * int(LeafT::DIM));
            auto leaf = std::make_unique<LeafT>(origin, openvdb::Vec3s(0.0f), false);
            const int zEnd = D == 3 ? int(LeafT::DIM) : 1;
            // Most leaves lie inside one lattice cell (far from the shapes the cells are larger
            // than a leaf): then the nodes in the cell's open interior, and those on one lower
            // face of it that lowerFaceInCell admits, are located in it directly (from the
            // cell size's table), which is what the search would find; only the other nodes on
            // its lower faces are searched.
            const int32_t cellIndex = leafCell(cursor, origin);
            const Cell* cell = cellIndex >= 0 ? &lattice.cells()[std::size_t(cellIndex)] : nullptr;
            std::array<bool, D> faceInCell{};
            const typename Interpolator::Location* table = nullptr;
            std::array<Vec<D>, SimplexLattice<D>::CORNERS> corner;
            if (cell) {
                for (int a = 0; a < D; ++a)
                    faceInCell[a] = lowerFaceInCell(cursor, *cell, origin, a);
                if (cell->log2Size <= MAX_TABLE_LOG2_SIZE) {
                    table = tables[std::size_t(cell->log2Size)].data();
                    for (std::size_t c = 0; c < corner.size(); ++c)
                        corner[c] = u.col(cell->corners[c]);
                }
            }
            for (int k = 0; k < zEnd; ++k) {
                for (int j = 0; j < int(LeafT::DIM); ++j) {
                    for (int i = 0; i < int(LeafT::DIM); ++i) {
                        const openvdb::Coord ijk = origin.offsetBy(i, j, k);
                        if (ijk[0] > n || ijk[1] > n || ijk[2] > (D == 3 ? n : 0)) continue;
                        Vec<D> x;
                        for (int a = 0; a < D; ++a)
                            x[a] = ijk[a] * H;
                        Vec<D> du = Vec<D>::Zero();
                        // In the open interior of the cell, or on one lower face of it that
                        // faceInCell admits.
                        bool interior = cell != nullptr;
                        int faces = 0;
                        for (int a = 0; a < D && interior; ++a) {
                            if (ijk[a] * scale > cell->origin[a]) continue;
                            interior = ++faces == 1 && faceInCell[a];
                        }
                        if (interior && table) {
                            // locateInCell and interpolate, read from the table.
                            const int side = 1 << cell->log2Size;
                            int entry = 0;
                            for (int a = D - 1; a >= 0; --a)
                                entry = entry * side + (ijk[a] * scale - cell->origin[a]);
                            const auto& loc = table[entry];
                            for (int m = 0; m <= D; ++m)
                                if (loc.weights[m] != 0)
                                    du += loc.weights[m] * corner[loc.nodes[m]];
                        } else if (interior) {
                            typename Interpolator::Location loc;
                            phi.locateInCell(std::size_t(cellIndex), x, loc);
                            du = Interpolator::interpolate(u, loc);
                        } else {
                            cursor.evaluate(u, x, du);
                        }
                        openvdb::Vec3s value(0.0f);
                        for (int a = 0; a < D; ++a) {
                            value[a] = float(du[a] * toWorld);
                            if (!std::isfinite(value[a])) bad[li] = 1;
                        }
                        leaf->setValueOn(ijk, value);
                    }
                }
            }
            leaves[li] = std::move(leaf);
        }
    };
    const tbb::blocked_range<std::size_t> all(0, leafCount);
    if (threaded) {
        tbb::parallel_for(all, fill);
    } else {
        fill(all);
    }
    for (char b : bad) {
        if (b) OPENVDB_THROW(openvdb::ValueError, "makeDeformationGrid: non-finite displacement");
    }

    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    for (auto& leaf : leaves)
        grid->tree().addLeaf(leaf.release());
    auto xform = openvdb::math::Transform::createLinearTransform(H * toWorld);
    const openvdb::Vec3d origin = placement.worldOrigin;
    xform->postTranslate(
        openvdb::Vec3d(origin.x(), origin.y(), D == 3 ? origin.z() : planeWorldZ(placement)));
    grid->setTransform(xform);
    grid->setName(DEFORMATION_GRID_NAME);
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    grid->setVectorType(openvdb::VEC_CONTRAVARIANT_RELATIVE);
    grid->setIsInWorldSpace(true);
    return grid;
}

openvdb::Vec3SGrid::Ptr
readDeformation(const std::string& path)
{
    // Lengths and offsets against the file size before OpenVDB allocates from them.
    checkVdbFileStructure(path, "readDeformation: cannot read '" + path + "':");
    openvdb::GridBase::Ptr base;
    try {
        openvdb::io::File file(path);
        file.open(false);
        if (!file.hasGrid(DEFORMATION_GRID_NAME)) {
            file.close();
            OPENVDB_THROW(openvdb::ValueError, "readDeformation: file '"
                                                   << path << "' has no grid named '"
                                                   << DEFORMATION_GRID_NAME << "'");
        }
        base = file.readGrid(DEFORMATION_GRID_NAME);
        file.close();
    } catch (const openvdb::ValueError&) {
        throw;
    } catch (const std::exception& e) {
        OPENVDB_THROW(openvdb::IoError,
                      "readDeformation: cannot read '" << path << "': " << e.what());
    }
    auto grid = openvdb::gridPtrCast<openvdb::Vec3SGrid>(base);
    if (!grid) {
        OPENVDB_THROW(openvdb::ValueError, "readDeformation: grid '"
                                               << DEFORMATION_GRID_NAME << "' in '" << path
                                               << "' is a " << base->valueType()
                                               << " grid, expected vec3s");
    }
    if (!grid->transform().isLinear() || !grid->hasUniformVoxels()) {
        OPENVDB_THROW(openvdb::ValueError, "readDeformation: grid in '"
                                               << path
                                               << "' must have a linear transform with uniform "
                                                  "voxels");
    }
    for (auto v = grid->cbeginValueAll(); v; ++v) {
        const openvdb::Vec3s x = *v;
        if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || !std::isfinite(x[2])) {
            OPENVDB_THROW(openvdb::ValueError,
                          "readDeformation: non-finite value in '" << path << "'");
        }
    }
    return grid;
}

template openvdb::Vec3SGrid::Ptr makeDeformationGrid<2>(const SimplexLattice<2>&,
                                                        const NodeVectors<2>&,
                                                        const UnitBoxPlacement&, int, bool);
template openvdb::Vec3SGrid::Ptr makeDeformationGrid<3>(const SimplexLattice<3>&,
                                                        const NodeVectors<3>&,
                                                        const UnitBoxPlacement&, int, bool);

} // namespace vdbmatch
