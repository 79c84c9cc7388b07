/// @file SurfacePieces.h
/// @brief The connected pieces of a surface, and the small ones among them: a scan's debris or
///        an outlier cluster floating beside the shape.
///
/// A piece is a set of elements joined by shared vertices. A small piece (below
/// SMALL_PIECE_SHARE of the surface's area in 3D, length in 2D) is rarely part of what a user
/// means to match: it widens the unit box the shapes are placed in (UnitBox.h), and the match
/// term pulls part of the other shape towards it. Measured on a 3D scan target with a closed
/// fragment (0.16% of its vertices) 5% of the box diagonal away (docs/results.md): the error in
/// world units +42%, min det 0.37 -> 0.003, and no part of the target left unreached, so the
/// target residual (MatchResult::targetResidual) does not tell. The CLI warns from these
/// figures before the run.
#pragma once

#include <vdbmatch/geometry/Surface.h>

#include <cstddef>
#include <vector>

namespace vdbmatch {

/// Share of a surface's measure below which a piece counts as small (SmallPieces).
constexpr double SMALL_PIECE_SHARE = 0.01;

/// One connected piece: the elements reachable from each other through shared vertices.
struct SurfacePiece
{
    std::size_t vertices = 0; ///< vertices used by its elements
    std::size_t elements = 0;
    double measure = 0;    ///< area (3D) or length (2D), in the surface's units
    openvdb::BBoxd box;    ///< of its vertices (z = 0 in 2D)
    std::size_t first = 0; ///< its lowest element index
};

/// The pieces of @a surface, largest measure first (ties: lower first element first), so the
/// result is deterministic. Vertices used by no element belong to no piece.
/// @throw openvdb::ValueError if an element index is out of range
template <int D> std::vector<SurfacePiece> surfacePieces(const Surface<D>& surface);

/// The small pieces of a surface, summed.
struct SmallPieces
{
    std::size_t pieces = 0;        ///< all pieces
    std::size_t small = 0;         ///< pieces below the share
    std::size_t smallVertices = 0; ///< their vertices
    double smallShare = 0;         ///< their measure over the surface's
    /// The largest distance between a small piece's box and the largest piece's box (0 when
    /// they overlap), in the surface's units.
    double farthest = 0;
};

/// surfacePieces() summed against @a share of the total measure (in (0, 1)).
/// @throw openvdb::ValueError if @a share is not in (0, 1) or an index is out of range
template <int D>
SmallPieces smallPieces(const Surface<D>& surface, double share = SMALL_PIECE_SHARE);

template <> std::vector<SurfacePiece> surfacePieces<2>(const Surface<2>&);
template <> std::vector<SurfacePiece> surfacePieces<3>(const Surface<3>&);
template <> SmallPieces smallPieces<2>(const Surface<2>&, double);
template <> SmallPieces smallPieces<3>(const Surface<3>&, double);

} // namespace vdbmatch
