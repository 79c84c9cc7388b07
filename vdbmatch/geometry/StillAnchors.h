/// @file StillAnchors.h
/// @brief Where two shapes coincide: points of M1 and M2 around which the other shape lies on
///        them, for the automatic anchors that hold still what an articulation leaves in place
///        (an addition to the paper, whose energy has no landmarks; docs/numerics.md "Automatic
///        anchors").
///
/// Where M1 and M2 coincide, the distances d1 and d2 cannot tell a tangential slide from no
/// motion, and the convex stored energies of eq:EsymMem spread a limb's stretch over the still
/// body (the "drag" of docs/results.md). The prior here is that what did not change did not move:
/// 1. a vertex x of M1 is *on M2* when |d2(x)| <= tolerance (d2 the narrow-band signed distance of
///    M2 at level, distanceBand(), sampled (bi/tri)linearly);
/// 2. it is *coincident* when every vertex of M1 within radius of it is on M2 (the set of
///    vertices on M2, eroded by radius), so the surfaces agree over a patch, not just where they
///    cross;
/// 3. the same for the vertices of M2 against M1 (d1), so that the anchors do not depend on
///    which shape is the source: the match M2 -> M1 holds the same points as M1 -> M2, and two
///    independent runs stay inverse to each other there;
/// 4. up to `count` of the coincident vertices of both shapes are chosen by farthest-point
///    sampling (in lexicographic order of their coordinates, from the first), spread over the
///    coincident region.
/// This holds for articulated motion (the body stays while limbs move) and fails for a
/// tangential motion of a surface that keeps its shape (a cylinder twisting about its axis, a
/// disc turning), which is why match() uses the anchors only when the paired extremities show
/// an articulation: some stays while another moves (ANCHOR_STILL_RATIO in Match.h). The result
/// does not depend on the thread count.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/Surface.h>

#include <cstddef>
#include <vector>

namespace vdbmatch {

/// Options of findStillAnchors(); lengths in Omega units.
struct StillAnchorOptions
{
    double tolerance = 0.002; ///< |d2| at most this: the vertex is on M2
    double radius = 0.03;     ///< the patch of M1 that must lie on M2 around an anchor
    std::size_t count = 100;  ///< most anchors returned
    /// Level of M2's distance band, h = 2^-level; <= 0 selects DEFAULT_LEVEL_2D/3D.
    int level = 0;
    bool threaded = true; ///< the distance uses TBB (the result does not depend on it)

    static constexpr int DEFAULT_LEVEL_2D = 9;
    static constexpr int DEFAULT_LEVEL_3D = 8;
};

/// The still anchors of one pair of shapes.
template <int D> struct StillAnchors
{
    std::vector<Vec<D>> points;       ///< anchors on M1 and M2, Omega units, in sampling order
    std::size_t vertices = 0;         ///< vertices of M1
    std::size_t onTarget = 0;         ///< ... within tolerance of M2
    std::size_t coincident = 0;       ///< ... whose whole radius-patch is within tolerance of M2
    std::size_t targetVertices = 0;   ///< vertices of M2
    std::size_t targetOnSource = 0;   ///< ... within tolerance of M1
    std::size_t targetCoincident = 0; ///< ... whose whole radius-patch is within tolerance of M1
    int level = 0;                    ///< the level of the distance bands

    /// Share of the vertices of both shapes that are coincident (the same either way round).
    double coincidentShare() const
    {
        const std::size_t all = vertices + targetVertices;
        return all ? double(coincident + targetCoincident) / double(all) : 0.0;
    }
};

/// The points of @a unitSource around which @a unitTarget coincides with it (see the file
/// comment). Both surfaces in Omega units.
/// @throw openvdb::ValueError if a surface fails checkSurface(), tolerance or radius is negative
///        or not finite, or the level is out of the range of distanceBand()
template <int D>
StillAnchors<D> findStillAnchors(const Surface<D>& unitSource, const Surface<D>& unitTarget,
                                 const StillAnchorOptions& opts = StillAnchorOptions());

extern template StillAnchors<2> findStillAnchors<2>(const Surface<2>&, const Surface<2>&,
                                                    const StillAnchorOptions&);
extern template StillAnchors<3> findStillAnchors<3>(const Surface<3>&, const Surface<3>&,
                                                    const StillAnchorOptions&);

} // namespace vdbmatch
