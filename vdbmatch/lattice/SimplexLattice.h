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
/// these grids (at most 8^d cells each; on small lattices a leaf is cut into slabs so that there
/// are at least 64 blocks to share between threads), in a fixed order; each block owns a local
/// list of the nodes its cells touch ("slots"), so that gradients are scattered without atomics
/// and gathered per node in block order (results independent of the thread count).
///
/// Nodes on the boundary of Omega carry the Dirichlet condition phi = Id (u = 0).
///
/// Hanging nodes (adaptive lattices, paper: "adaptive octree grids refined only around the
/// shapes"). Where cells of side 2^s h meet cells of side 2^{s-1} h, some nodes of the small
/// cells lie inside an edge or (3D) a face of a large cell. The P1 function stays continuous
/// only if its value there is the one of the large cell's linear pieces, which fixes it in terms
/// of the large cell's corners. With 2:1 balance (neighbouring cells differ in size by at most
/// a factor 2 across faces, edges and corners) the only hanging nodes are
/// - edge midpoints m = (a + b)/2 of a large edge [a, b]:      u(m) = (u(a) + u(b)) / 2;
/// - face centres c of a large square face (3D), min corner a and max corner b:
///   u(c) = (u(a) + u(b)) / 2.
/// Every Kuhn simplex edge joins corners v <= w componentwise, so a square face is split along
/// the diagonal from its min to its max corner; the face centre lies on that diagonal, the four
/// small faces' diagonals lie inside the two large triangles (the triangulations nest), and the
/// constrained function is exactly the large cell's linear function on the face: continuity.
/// A master may itself be hanging (a corner of a cell of side 2^s can be an edge midpoint of a
/// cell of side 2^{s+1}); the constraints are resolved transitively, so that every hanging node
/// is an affine combination (weights > 0, sum 1) of non-hanging nodes only. Write P for the
/// resulting prolongation from the free nodes (neither boundary nor hanging) to all nodes:
/// expand() applies P to nodal vectors, reduce() applies P^T to co-vectors (gradients). A
/// hanging node on the boundary of Omega is a Dirichlet node (its masters are boundary nodes).
/// fromCellMasks() validates the 2:1 balance on every node (a node inside an edge or face of a
/// cell must be its midpoint / centre) and that cells do not overlap.
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

/// Size figures of a lattice (SimplexLattice::stats()).
struct LatticeStats
{
    std::vector<std::size_t> cellsPerLog2Size; ///< [s]: number of cells of side 2^s h
    std::size_t nodes = 0;                     ///< all nodes
    std::size_t freeNodes = 0;     ///< unknowns of the descent: neither boundary nor hanging
    std::size_t hangingNodes = 0;  ///< constrained nodes (boundary ones included)
    std::size_t boundaryNodes = 0; ///< Dirichlet nodes (hanging ones included)
    std::size_t denseNodes = 0;    ///< (2^l + 1)^D, the nodes of the dense lattice of the level
};

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
    /// index axes are used (2D: z = 0). Finds the hanging nodes and their resolved constraints
    /// (file comment). Cost: O(nodes * sizes) tree look-ups, in parallel.
    /// @throw openvdb::ValueError for a level outside [1, 12], a cell outside the unit box,
    ///        overlapping cells (a node inside a cell), or cells of mixed sizes that violate the
    ///        2:1 balance (a node inside an edge or face of a cell other than its midpoint or
    ///        centre).
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

    /// True if node i lies inside an edge or face of a larger cell (its value is constrained).
    bool isHangingNode(std::size_t i) const { return mHangingIndex[i] >= 0; }
    std::size_t hangingNodeCount() const { return mHangingNodes.size(); }
    /// True if node i is an unknown of the descent: neither a boundary nor a hanging node.
    bool isFreeNode(std::size_t i) const { return !isHangingNode(i) && !isBoundaryNode(i); }
    std::size_t freeNodeCount() const { return mFreeNodeCount; }
    /// The hanging nodes in increasing node order; constraint k belongs to hangingNodes()[k].
    const std::vector<int32_t>& hangingNodes() const { return mHangingNodes; }
    /// k such that hangingNodes()[k] = i, or -1 if node i is not hanging.
    int32_t hangingIndex(std::size_t i) const { return mHangingIndex[i]; }
    /// Resolved constraints, CSR over the hanging nodes: u(hangingNodes()[k]) = sum over
    /// j in [constraintOffsets()[k], constraintOffsets()[k+1]) of
    /// constraintWeights()[j] * u(constraintMasters()[j]). Masters are non-hanging nodes in
    /// increasing order, weights are positive dyadic numbers summing to 1.
    const std::vector<std::size_t>& constraintOffsets() const { return mConstraintOffsets; }
    const std::vector<int32_t>& constraintMasters() const { return mConstraintMasters; }
    const std::vector<Real>& constraintWeights() const { return mConstraintWeights; }

    /// u <- P u: sets every hanging column of @a u (D x nodeCount) to the weighted sum of its
    /// masters' columns; other columns unchanged. Deterministic; serial (O(hanging nodes)).
    void expand(NodeVectors<D>& u) const;
    /// g <- P^T g for a co-vector (e.g. an energy gradient, D x nodeCount): adds
    /// w * g(:, hanging) to each master column, then zeroes the hanging columns. Fixed serial
    /// order (deterministic). <reduce(g), v> = <g, expand(v)> for every v (transpose of P).
    void reduce(NodeVectors<D>& g) const;

    /// Cell and node counts.
    LatticeStats stats() const;

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
    /// Classifies the nodes and resolves the hanging-node constraints (fromCellMasks()).
    void findHangingNodes(const std::vector<openvdb::MaskGrid::ConstPtr>& masks,
                          const std::vector<char>& hasCells);

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
    std::vector<int32_t> mHangingIndex; ///< per node: index into mHangingNodes or -1
    std::vector<int32_t> mHangingNodes;
    std::vector<std::size_t> mConstraintOffsets{0};
    std::vector<int32_t> mConstraintMasters;
    std::vector<Real> mConstraintWeights;
    std::size_t mFreeNodeCount = 0;
};

/// The Kuhn split: for simplex p of a cell, kuhnPath<D>(p)[m] is the corner bitmask of v_m and
/// kuhnAxis<D>(p)[m] (m >= 1) the axis pi(m) of the step v_{m-1} -> v_m.
template <int D> struct KuhnSplit
{
    static const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>& path();
    static const std::array<std::array<int, D + 1>, (D == 2 ? 2 : 6)>& axis();
};

} // namespace vdbmatch
