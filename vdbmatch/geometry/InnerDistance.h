/// @file InnerDistance.h
/// @brief F_k, the inner distance from one of a shape's paired extremities: the length of the
///        shortest path inside the shape to a given point, for the inner-distance term
///        (an addition to the paper, whose energy sees only the distances d1, d2 to the surfaces;
///        energy/InnerDistanceTerm.h, docs/numerics.md "The inner distance").
///
/// An articulation bends a limb at its joints and keeps its length, so it keeps F_k along the
/// limb; d1 and d2 do not see a slide of the skin along the limb, F_k does.
///
/// On the dense lattice of spacing h = 2^-level in Omega:
/// 1. the inside is the set of nodes with signed distance < 0 (the sign of a narrow band,
///    distanceBand());
/// 2. F_k solves the eikonal equation |grad F| = 1 inside, F = |x - p_k| at the corners of the
///    cell containing the source point p_k (those inside), by the first-order fast marching
///    method (upwind quadratic update over the 2D axis neighbours): unlike the graph distance
///    of Extremities.h (8% too long along 22.5 degrees on the 8-neighbour grid), its error does
///    not depend much on the direction of a limb, so two poses of one limb get the same F;
/// 3. outside, F_k is continued from the inside values (the inside keeps its own) in increasing
///    distance u from the inside, each node taking the upwind eikonal value of F from its
///    neighbours already set: F_k is defined and finite on the whole box, where phi(x) of a
///    point near M1 may land, and next to the surface it comes from the surface's own side.
///    A march of F itself would carry the smaller values of the far side of a gap of the
///    outside (a hand hanging beside the hip, the slot of a U) to the nodes next to the near
///    side, and from them into the interpolant at its surface points; continued by u, F jumps
///    where the two sides meet, in the middle of the gap, instead.
/// Nodes are accepted one at a time in increasing F inside and increasing u outside (ties by
/// index), one source after the other or in parallel, so the result does not depend on the
/// thread count. Values are stored
/// as floats (the interpolant of the stored values is what the term differentiates).
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/Surface.h>

#include <cstddef>
#include <vector>

namespace vdbmatch {

/// F_k on the nodes of a dense lattice of [0,1]^D, sampled multilinearly.
template <int D> struct InnerDistanceField
{
    int level = 0;
    int n = 0;  ///< cells per axis (2^level); (n+1)^D nodes, x fastest
    Real h = 0; ///< 2^-level
    /// F per node, Omega units; +infinity only when no source could be placed (empty()).
    std::vector<float> values;
    std::size_t insideNodes = 0;   ///< nodes inside the shape
    std::size_t sourceNodes = 0;   ///< nodes seeded from the source point
    std::size_t reachedInside = 0; ///< inside nodes reached by the march from the sources

    bool empty() const { return sourceNodes == 0; }

    /// F at @a x by multilinear interpolation of the nodes, and its gradient (that of the
    /// interpolant, exact in the interior of a cell). Points outside [0,1]^D are clamped to it
    /// (F constant outside, gradient 0 across the clamped axes). False if empty().
    bool sample(const Vec<D>& x, Real& f, Vec<D>* gradient = nullptr) const;
};

/// F_k of a closed surface given in Omega units for each of @a sources (Omega units; typically
/// its paired extremities, Extremities.h): element k of the result is the inner distance from
/// source k. A source seeds the inside corners of its cell, or, when its cell has none, the
/// inside node nearest to it (F = the distance to it).
/// @throw openvdb::ValueError if the surface fails checkSurface(), the level is out of the range
///        of distanceBand(), or a source is not finite
template <int D>
std::vector<InnerDistanceField<D>> innerDistanceFields(const Surface<D>& unitSurface,
                                                       const std::vector<Vec<D>>& sources,
                                                       int level, bool threaded = true);

/// A point's own source: the index of the field least at @a x, with that least value in
/// @a value, or -1 when another field is less than @a ratio times that value there. A point
/// about as near to two extremities (the body between two limbs, a hand hanging by the hip)
/// has paths from both crossing a joint, which an articulation turns; a point on a limb, near
/// its end, has one extremity clearly its own (MatchOptions::innerDistanceRatio).
/// Empty fields are skipped; -1 when every field is empty.
/// @throw openvdb::ValueError if @a ratio is not finite or below 1
template <int D>
int ownSource(const std::vector<InnerDistanceField<D>>& fields, const Vec<D>& x, double ratio,
              Real& value);

extern template struct InnerDistanceField<2>;
extern template struct InnerDistanceField<3>;
extern template std::vector<InnerDistanceField<2>>
innerDistanceFields<2>(const Surface<2>&, const std::vector<Vec<2>>&, int, bool);
extern template std::vector<InnerDistanceField<3>>
innerDistanceFields<3>(const Surface<3>&, const std::vector<Vec<3>>&, int, bool);
extern template int ownSource<2>(const std::vector<InnerDistanceField<2>>&, const Vec<2>&, double,
                                 Real&);
extern template int ownSource<3>(const std::vector<InnerDistanceField<3>>&, const Vec<3>&, double,
                                 Real&);

} // namespace vdbmatch
