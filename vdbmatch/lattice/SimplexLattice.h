/// @file SimplexLattice.h
/// @brief Cells, nodes and Kuhn simplices of one multiscale level: the domain of the
///        piecewise-linear deformation phi = Id + u (paper sec:numerics).
///
/// A level l has spacing h = 2^{-l}; node (i, j, k) sits at x = (i, j, k) h in Omega = (0,1)^d
/// ("index" coordinates are integers at this finest spacing). A cell of size 2^s h has its
/// minimum corner at an index coordinate divisible by 2^s and is split into d! simplices by the
/// Kuhn (Freudenthal) rule: for each permutation pi of the axes the path
/// v_0 = origin, v_m = v_{m-1} + 2^s e_{pi(m)}. Every cell of every size uses the same rule, so
/// a cell's simplices are unions of the simplices of its 2^d children: refinement is nested and a
/// piecewise-linear phi is reproduced exactly (det D phi survives prolongation).
///
/// Cells are held as OpenVDB topology: one MaskGrid per cell size 2^s, voxel (a,b,c) of grid s
/// being the cell with origin 2^s (a,b,c). The assembly runs over "blocks", one per leaf node of
/// these grids (at most 8^d cells each), in a fixed order; each block owns a local list of the
/// nodes its cells touch ("slots"), so that gradients are scattered without atomics and gathered
/// per node in block order (results independent of the thread count).
///
/// Nodes on the boundary of Omega carry the Dirichlet condition phi = Id (u = 0).
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>

#include <openvdb/openvdb.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vdbmatch {

/// Nodal vector field on a lattice: column i is the value at node i.
template <int D> using NodeVectors = Eigen::Matrix<Real, D, Eigen::Dynamic>;

template <int D> class SimplexLattice
{
public:
    static constexpr int CORNERS = 1 << D;           ///< nodes per cell
    static constexpr int SIMPLICES = D == 2 ? 2 : 6; ///< Kuhn simplices per cell

    struct Cell
    {
        openvdb::Coord origin;                ///< minimum corner, index coordinates
        int log2Size;                         ///< cell side = 2^log2Size h
        std::array<int32_t, CORNERS> corners; ///< node index of corner with bit a = +side along a
    };

    struct Block
    {
        std::size_t cellBegin, cellEnd; ///< range in cells()
        std::size_t slotBegin, slotEnd; ///< range in slotNodes(): the nodes touched by the block
    };

    /// Builds a lattice at level @a level from cell masks: masks[s] holds the cells of side
    /// 2^s h (voxel coordinates = origin / 2^s); null entries are skipped. Only the first D
    /// index axes are used (2D: z = 0). Throws openvdb::ValueError for a level outside [1, 12]
    /// or a cell outside the unit box.
    static SimplexLattice fromCellMasks(int level,
                                        const std::vector<openvdb::MaskGrid::ConstPtr>& masks);

    /// Every cell of side h in the unit box.
    static SimplexLattice dense(int level);

    /// Cells of side h whose index-space box intersects @a bbox (clipped to the unit box).
    static SimplexLattice box(int level, const openvdb::CoordBBox& bbox);

    int level() const { return mLevel; }
    int resolution() const { return 1 << mLevel; } ///< N = 2^l, nodes 0..N per axis
    Real h() const { return mH; }

    std::size_t nodeCount() const { return mNodeCoords.size(); }
    const openvdb::Coord& nodeCoord(std::size_t i) const { return mNodeCoords[i]; }
    /// Position of node i in Omega units.
    Vec<D> nodePosition(std::size_t i) const;
    /// All node positions (Omega units).
    NodeVectors<D> nodePositions() const;
    /// True if node i lies on the boundary of Omega (Dirichlet node, u = 0).
    bool isBoundaryNode(std::size_t i) const;
    /// Node index at index coordinate @a ijk, or -1.
    int32_t findNode(const openvdb::Coord& ijk) const;

    std::size_t cellCount() const { return mCells.size(); }
    std::size_t simplexCount() const { return mCells.size() * SIMPLICES; }
    const std::vector<Cell>& cells() const { return mCells; }
    const std::vector<Block>& blocks() const { return mBlocks; }
    /// Node index of each slot.
    const std::vector<int32_t>& slotNodes() const { return mSlotNodes; }
    /// Slot (index into slotNodes()) of corner c of cell i: cellSlots()[i * CORNERS + c].
    const std::vector<int32_t>& cellSlots() const { return mCellSlots; }

    /// Sums per-slot vectors into per-node vectors in a fixed order (block order), in parallel
    /// over nodes: out.col(n) = sum of perSlot.col(s) over the slots s of node n.
    void gatherSlots(const NodeVectors<D>& perSlot, NodeVectors<D>& out,
                     bool threaded = true) const;

    /// The displacement u as a sparse OpenVDB vector grid on the nodes (voxel size h, voxel
    /// (i,j,k) = node (i,j,k), z component 0 in 2D), named "displacement", vector type
    /// contravariant relative, Omega units.
    openvdb::Vec3dGrid::Ptr toGrid(const NodeVectors<D>& u) const;
    /// Reads node values from a grid with the node layout of toGrid(); nodes without an active
    /// value get 0. Throws openvdb::ValueError if the voxel size is not h.
    NodeVectors<D> fromGrid(const openvdb::Vec3dGrid& grid) const;

private:
    SimplexLattice() = default;

    int mLevel = 0;
    Real mH = 1;
    std::vector<openvdb::Coord> mNodeCoords;
    openvdb::Int32Grid::Ptr mNodeIndex;
    std::vector<Cell> mCells;
    std::vector<Block> mBlocks;
    std::vector<int32_t> mSlotNodes;
    std::vector<int32_t> mCellSlots;
    std::vector<std::size_t> mGatherBegin; ///< CSR over nodes into mGatherSlots
    std::vector<int32_t> mGatherSlots;
};

/// The Kuhn split: for simplex p of a cell, kuhnPath<D>(p)[m] is the corner bitmask of v_m and
/// kuhnAxis<D>(p)[m] (m >= 1) the axis pi(m) of the step v_{m-1} -> v_m.
template <int D> struct KuhnSplit
{
    static const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>& path();
    static const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>& axis();
};

} // namespace vdbmatch
