/// @file Extremities.h
/// @brief The extremities of a shape (limb tips, head, tail): the ends of its branches, found by
///        the inner distance, for automatic landmarks (an addition to the paper, whose energy
///        has no landmarks; docs/numerics.md "Automatic landmarks").
///
/// On the nodes of the dense lattice of spacing h = 2^-level in Omega that lie inside the shape
/// (signed distance < 0: the sign of a narrow band, distanceBand()), joined to their 3^D - 1
/// neighbours by segments of length h |offset|:
/// 1. the root r is a deepest node (of those within h of the largest depth, the one nearest to
///    their centroid; the depth is the band's distance, carried inside by graph distance) and
///    f(x) the graph distance from r inside the shape (Dijkstra), an
///    approximation of the inner distance, which articulation changes little;
/// 2. every local maximum of f is the end of a branch, and its persistence the length of that
///    branch: in the superlevel sets {f >= t}, t decreasing, the maximum starts a component, and
///    when two components meet at a node v, the one whose maximum is lower ends there, with
///    persistence f(max) - f(v) (0-dimensional persistence, union-find); the global maximum has
///    persistence max f;
/// 3. the extremities are the maxima whose persistence is at least minPersistence times max f:
///    limbs are long, bumps of the surface and the corners of the lattice short;
/// 4. each is placed at the centroid of its branch's end (Extremities::points).
/// Only the component of the root counts (a shape in several pieces gives the extremities of
/// its deepest piece). The result does not depend on the thread count.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/Surface.h>

#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace vdbmatch {

/// Options of findExtremities().
struct ExtremityOptions
{
    /// Level of the interior lattice, h = 2^-level; <= 0 selects DEFAULT_LEVEL_2D/3D.
    int level = 0;
    /// A branch is an extremity when its persistence is at least this fraction of max f.
    double minPersistence = 0.1;
    bool threaded = true; ///< the signed distance uses TBB (the result does not depend on it)

    static constexpr int DEFAULT_LEVEL_2D = 8;
    static constexpr int DEFAULT_LEVEL_3D = 6;
};

/// The extremities of one shape, most persistent first.
template <int D> struct Extremities
{
    /// The ends of the branches, Omega units: the centroid of the nodes of the branch within
    /// rho = min(persistence / 2, depth of the root) of its tip in f (connected to the tip),
    /// steadier than the tip itself, which can jump between the toe and the heel of a foot
    /// when the pose changes.
    std::vector<Vec<D>> points;
    std::vector<Vec<D>> tips;        ///< the maxima of f, Omega units
    std::vector<double> persistence; ///< branch lengths, Omega units
    /// Inner distances between the extremities (k x k, symmetric, zero diagonal), Omega units.
    Eigen::MatrixXd innerDistance;
    Vec<D> root = Vec<D>::Zero(); ///< the deepest node
    double maxRootDistance = 0;   ///< max f, Omega units
    std::size_t insideNodes = 0;  ///< nodes of the root's component
    int level = 0;                ///< the level used

    std::size_t size() const { return points.size(); }
};

/// The extremities of a closed surface given in Omega units.
/// A shape with no lattice node inside (thinner than h everywhere) has no extremities and
/// insideNodes = 0.
/// @throw openvdb::ValueError if the surface fails checkSurface(), the level is out of the range
///        of distanceBand(), or minPersistence is not in (0, 1]
template <int D>
Extremities<D> findExtremities(const Surface<D>& unitSurface,
                               const ExtremityOptions& opts = ExtremityOptions());

extern template Extremities<2> findExtremities<2>(const Surface<2>&, const ExtremityOptions&);
extern template Extremities<3> findExtremities<3>(const Surface<3>&, const ExtremityOptions&);

} // namespace vdbmatch
