/// @file Prolongation.h
/// @brief Exact prolongation of a piecewise-linear displacement from a coarse lattice to a finer
///        one, and point evaluation of a piecewise-linear field on a lattice (paper
///        sec:numerics: the result of one level "is interpolated into the next finer one").
///
/// The value at a point x is the P1 interpolant of the nodal values on the Kuhn simplex that
/// contains x. In a cell with origin o and side s, with local coordinates t = (x - o)/s in
/// [0,1]^D, the containing simplex is the one whose path visits the axes by decreasing t:
/// t_{pi(1)} >= ... >= t_{pi(D)}, and the barycentric weights are
/// @f[ \lambda_0 = 1 - t_{\pi(1)},\quad \lambda_m = t_{\pi(m)} - t_{\pi(m+1)},\quad
///     \lambda_D = t_{\pi(D)} @f]
/// on the path vertices v_m (SimplexLattice, KuhnSplit). Ties (x on a face) give zero weights to
/// the vertices that differ, so every containing simplex gives the same value.
///
/// Because the Kuhn split is nested, every fine simplex lies in one coarse simplex and the
/// prolongated phi = Id + u has, on each fine simplex, the D phi of the coarse simplex
/// containing it: det D phi > 0 survives the prolongation, and so do the volume energies
/// (tests/multiscale/TestProlongation.cc). Node coordinates are dyadic, so t and the weights
/// are computed without rounding; only the weighted sum rounds.
///
/// A point outside every cell of the coarse lattice gets u = 0 (the identity deformation): on
/// lattices covering Omega this happens only outside Omega; on adaptive lattices it is the
/// value phi = Id that the Dirichlet condition gives far from the shapes.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/openvdb.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace vdbmatch {
namespace multiscale {

/// Finds the Kuhn simplex of a lattice containing a point. Holds one cell-index grid per cell
/// size. Thread-safety: const queries may be called concurrently.
template <int D> class PiecewiseLinearInterpolator
{
public:
    /// The nodes of a simplex and the barycentric weights of a point in it.
    struct Location
    {
        std::array<int32_t, D + 1> nodes;
        std::array<Real, D + 1> weights;
    };

    /// @param lattice  must outlive the interpolator
    explicit PiecewiseLinearInterpolator(const SimplexLattice<D>& lattice);

    const SimplexLattice<D>& lattice() const { return *mLattice; }

    /// Locates @a x (Omega units). Returns false if no cell of the lattice contains x (closed
    /// cells: points on faces belong to every adjacent cell).
    bool locate(const Vec<D>& x, Location& loc) const;

    /// The P1 interpolant of @a u (D x nodeCount) at a located point: sum_m weights[m] u(nodes[m]),
    /// zero weights skipped (the same sum evaluate() forms).
    static Vec<D> interpolate(const NodeVectors<D>& u, const Location& loc);

    /// Value of the piecewise-linear field @a u (D x nodeCount) at @a x; false (and @a value
    /// unchanged) if no cell contains x.
    bool evaluate(const NodeVectors<D>& u, const Vec<D>& x, Vec<D>& value) const;

    /// The same queries through cached tree accessors, for many nearby points from one thread
    /// (the results equal the interpolator's own, bit for bit). Not thread-safe: one per thread.
    class Cursor
    {
    public:
        explicit Cursor(const PiecewiseLinearInterpolator& interpolator);
        bool locate(const Vec<D>& x, Location& loc);
        bool evaluate(const NodeVectors<D>& u, const Vec<D>& x, Vec<D>& value);
        /// Index of a cell containing @a x (the one locate() uses), or -1 if there is none.
        int32_t cell(const Vec<D>& x);

    private:
        const PiecewiseLinearInterpolator* mInterpolator;
        std::vector<std::unique_ptr<openvdb::Int32Grid::ConstAccessor>> mAccessors;
    };

    /// Locates @a x in cell @a cellIndex of the lattice, which must contain it. For x in the
    /// open interior of the cell this is the location locate() finds, to the last bit (no other
    /// cell contains such a point); for many points of one cell it saves the search.
    void locateInCell(std::size_t cellIndex, const Vec<D>& x, Location& loc) const;

    /// The locations of the lattice-index points of a cell of side 2^log2Size, from its origin:
    /// entry l_0 + S (l_1 + S l_2) (S = 2^log2Size, 0 <= l_a < S) holds the weights and, as
    /// nodes, the corner indices (bit a: the upper corner along axis a) that locateInCell()
    /// gives at origin + l, to the last bit. For many points of cells of one size.
    static std::vector<Location> cellTable(int log2Size);

private:
    /// locate() with @a cellAt(s, ijk) giving the index of the cell of side 2^s at ijk (or -1);
    /// the index of the cell found goes to @a found if given.
    template <typename CellAt>
    bool locateWith(const Vec<D>& x, Location& loc, CellAt&& cellAt,
                    int32_t* found = nullptr) const;
    /// The simplex of @a cell containing the lattice index point @a p, and its weights.
    static void simplexIn(const typename SimplexLattice<D>::Cell& cell, const Vec<D>& p,
                          Location& loc);

    const SimplexLattice<D>* mLattice;
    /// mCellIndex[s]: voxel origin/2^s -> index of the cell of side 2^s h, or null if none.
    std::vector<openvdb::Int32Grid::Ptr> mCellIndex;
};

/// The P1 interpolant of @a uCoarse (on @a coarse) at every node of @a fine; nodes of @a fine
/// outside every coarse cell get 0.
/// @throw openvdb::ValueError if fine.level() < coarse.level() or uCoarse has the wrong size
template <int D>
NodeVectors<D> prolongate(const SimplexLattice<D>& coarse, const NodeVectors<D>& uCoarse,
                          const SimplexLattice<D>& fine, bool threaded = true);

extern template class PiecewiseLinearInterpolator<2>;
extern template class PiecewiseLinearInterpolator<3>;

} // namespace multiscale
} // namespace vdbmatch
