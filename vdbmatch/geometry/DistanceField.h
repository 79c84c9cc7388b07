/// @file DistanceField.h
/// @brief Signed distance grids of explicit surfaces on the nodes of Omega, and the tiered
///        FieldSampler of a shape that covers all of Omega.
///
/// For a surface M (Surface.h) the signed distance
/// @f[ d(x) = \pm \operatorname{dist}(x, M), \qquad d < 0 \text{ inside}, @f]
/// is sampled on the nodes x = ijk h, h = 2^-level, of Omega = (0,1)^D (the surface must already
/// be in Omega units, see transformed()). The grids are level sets with the transform
/// ijk -> ijk h (no offset), the input of ShapeFields / FieldSampler. In 2D they are slices
/// k = 0 (ShapeFields reads only that layer).
///
/// Methods:
/// - 3D: tools::meshToVolume (the sign comes from a flood fill of the exterior, so the
///   orientation of the triangles does not matter; it also records the closest triangle of every
///   voxel), then every active value is replaced by the exact distance to the triangles: the
///   nearest of the triangles recorded for the voxel and its 26 neighbours, improved by steepest
///   descent over triangles sharing a vertex. (meshToVolume's own values were off by up to 0.43
///   voxel 3-4 voxels from a sphere; after this pass the error is that of the mesh.)
/// - 2D: exact point-segment distances, per 8x8 node tile over the segments that can be nearest
///   (those within d(tile centre) + tile diameter of the centre); the sign by the parity of the
///   crossings of the row y = j h left of the node (half-open rule at vertices, so a vertex on a
///   row is counted once), i.e. even-odd inside; orientation does not matter.
///
/// The paper's matching energy samples d2 at phi(x) for every x, so the solver needs d valid on
/// all of Omega (far from the shapes) and accurate near them: buildShapeSampler() stacks a narrow
/// band at the working level over a dense grid at a coarse level.
/// @see paper [subsec:notation], [eq:EsymMatch]
#pragma once

#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/geometry/ShapeFields.h>
#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <openvdb/openvdb.h>

#include <map>
#include <utility>

namespace vdbmatch {

/// Levels accepted by the distance functions (h = 2^-level), as SimplexLattice.
constexpr int MIN_DISTANCE_LEVEL = 1;
constexpr int MAX_DISTANCE_LEVEL = 12;

/// Smallest half width accepted, voxels: OpenVDB level sets have a background of at least 3
/// voxels (tools::checkLevelSet check 4, which ShapeFields runs).
constexpr double MIN_DISTANCE_HALF_WIDTH_VOXELS = 3.0;

/// Nodes added around [0, 2^level]^D by buildShapeSampler() for the dense tier. The fields of a
/// node need its 3^D neighbours and the sampler's stencil 3^D nodes with fields, so a padding of
/// p nodes covers queries up to p - 1.5 voxels of that tier beyond the box: with 4, 2.5 voxels.
constexpr int SAMPLER_BOX_PADDING = 4;

/// Narrow-band signed distance of a surface in Omega units.
/// @param surface          closed surface (checkSurface), Omega units
/// @param level            h = 2^-level, in [MIN_DISTANCE_LEVEL, MAX_DISTANCE_LEVEL]
/// @param halfWidthVoxels  band half width in voxels, >= MIN_DISTANCE_HALF_WIDTH_VOXELS
/// @param threaded         use TBB (the 3D path always does, inside OpenVDB)
/// @return a level set ("surface", transform ijk -> ijk h), negative inside, active with the
///         true distance (Omega units) on every node with |d| <= halfWidth h, inactive values
///         ±background, background halfWidth h. 2D: slice k = 0.
/// @throw openvdb::ValueError if the surface fails checkSurface or an argument is out of range
template <int D>
openvdb::FloatGrid::Ptr distanceBand(const Surface<D>& surface, int level, double halfWidthVoxels,
                                     bool threaded = true);

/// Signed distance on every node of the box [-padding, 2^level + padding]^D (2D: k = 0), for the
/// coarse tier of buildShapeSampler(). 3D: meshToVolume with a band wide enough to reach every
/// node of the box (bounded from the vertices); 2D: the exact tile method on every tile of the
/// box. Nodes outside the box may be active too (true distances as well).
/// @return a level set as distanceBand(), background max(3 h, largest |d|)
/// @throw openvdb::ValueError if the surface fails checkSurface or an argument is out of range
/// @throw openvdb::RuntimeError if the result does not cover the box (an internal error)
template <int D>
openvdb::FloatGrid::Ptr distanceBox(const Surface<D>& surface, int level,
                                    int padding = UNIT_BOX_NODE_PADDING, bool threaded = true);

/// Options of buildShapeSampler().
struct ShapeSamplerOptions
{
    ShapeFieldOptions fields;       ///< options of the field computation (all tiers)
    double bandHalfWidthVoxels = 8; ///< half width of the band tiers, voxels of their level
    int denseLevel3D = 5;           ///< level of the dense (box) tier in 3D, at most
    int denseLevel2D = 7;           ///< level of the dense (box) tier in 2D, at most
    bool threaded = true;           ///< use TBB (results do not depend on it)
};

/// FieldSampler of a shape valid on all of Omega: tiers, finest first,
/// 1. distanceBand at @a level,
/// 2. distanceBand at level - 2 if level - 2 > dense level,
/// 3. distanceBox at min(level, dense level) with SAMPLER_BOX_PADDING,
/// so every point of [-2.5 hc, 1 + 2.5 hc]^D (hc the voxel of the dense tier) is covered, and
/// points within about halfWidth - 1.5 voxels of the surface use the finest tier.
/// @param surface  closed surface, Omega units
/// @throw openvdb::ValueError as distanceBand, distanceBox and FieldSampler
template <int D>
typename FieldSampler<D>::ConstPtr
buildShapeSampler(const Surface<D>& surface, int level,
                  const ShapeSamplerOptions& opts = ShapeSamplerOptions());

/// The tiers buildShapeSampler() built for one shape, kept for its next levels: above the dense
/// level the box tier is the same at every level, and the band two levels down was the finest
/// tier two levels before. Band tiers more than two levels below the last request are dropped.
/// Not thread-safe: one cache per shape.
template <int D> class ShapeSamplerCache
{
public:
    /// Tiers of @a kind ('b' band, 'x' box) at @a level, built by @a build on the first request.
    template <typename Build>
    typename FieldSampler<D>::ConstPtr tier(char kind, int level, Build&& build)
    {
        const auto key = std::make_pair(kind, level);
        auto it = mTiers.find(key);
        if (it == mTiers.end()) it = mTiers.emplace(key, build()).first;
        return it->second;
    }
    /// Forgets the band tiers below @a level - 2.
    void dropBelow(int level)
    {
        for (auto it = mTiers.begin(); it != mTiers.end();)
            it = it->first.first == 'b' && it->first.second < level - 2 ? mTiers.erase(it) : ++it;
    }
    /// Binds the cache to @a surface on first use; false if it holds another surface's tiers.
    bool claim(const void* surface)
    {
        if (mOwner && mOwner != surface) return false;
        mOwner = surface;
        return true;
    }

private:
    const void* mOwner = nullptr;
    std::map<std::pair<char, int>, typename FieldSampler<D>::ConstPtr> mTiers;
};

/// As above, reusing (and filling) @a cache, which must only ever be used with this @a surface
/// and @a opts. Bitwise the same sampler as without the cache.
/// @throw openvdb::ValueError as above, or if @a cache was used with another surface
template <int D>
typename FieldSampler<D>::ConstPtr buildShapeSampler(const Surface<D>& surface, int level,
                                                     const ShapeSamplerOptions& opts,
                                                     ShapeSamplerCache<D>& cache);

/// Level set of a surface for output (e.g. the deformed shape) in a given transform.
/// - 3D: the 3D method above in the index space of @a xform (linear, uniform voxels).
/// - 2D: a slice grid k = 0 from the 2D method in the index space of @a xform, which must be a
///   uniform scale plus a translation (world (x, y, 0) then maps to index (i, j, k0); the slice
///   is written at k = 0).
/// @param worldSurface     closed surface in the world space of @a xform
/// @param halfWidthVoxels  >= MIN_DISTANCE_HALF_WIDTH_VOXELS
/// @return class level set, name "surface", background halfWidth * voxel size
/// @throw openvdb::ValueError if the surface fails checkSurface, the half width is out of range,
///        the transform is not linear with uniform voxels (3D) or not a uniform scale plus
///        translation (2D)
template <int D>
openvdb::FloatGrid::Ptr
levelSetFromSurface(const Surface<D>& worldSurface, const openvdb::math::Transform& xform,
                    double halfWidthVoxels = MIN_DISTANCE_HALF_WIDTH_VOXELS);

template <> openvdb::FloatGrid::Ptr distanceBand<2>(const Surface<2>&, int, double, bool);
template <> openvdb::FloatGrid::Ptr distanceBand<3>(const Surface<3>&, int, double, bool);
template <> openvdb::FloatGrid::Ptr distanceBox<2>(const Surface<2>&, int, int, bool);
template <> openvdb::FloatGrid::Ptr distanceBox<3>(const Surface<3>&, int, int, bool);
template <>
openvdb::FloatGrid::Ptr levelSetFromSurface<2>(const Surface<2>&, const openvdb::math::Transform&,
                                               double);
template <>
openvdb::FloatGrid::Ptr levelSetFromSurface<3>(const Surface<3>&, const openvdb::math::Transform&,
                                               double);
extern template FieldSampler<2>::ConstPtr buildShapeSampler<2>(const Surface<2>&, int,
                                                               const ShapeSamplerOptions&);
extern template FieldSampler<3>::ConstPtr buildShapeSampler<3>(const Surface<3>&, int,
                                                               const ShapeSamplerOptions&);

} // namespace vdbmatch
