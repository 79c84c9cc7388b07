/// @file ShapeDistance.h
/// @brief The domain Omega of a deformation grid as a placement, and the signed distance to an
///        input shape at any world point, for the evaluation tools (Consistency.h, SliceImage.h).
///
/// Omega is the world box of the deformation grid's nodes (DeformationField::worldBounds()); its
/// side (the largest extent over the dim() axes) is the "domain size" every relative figure is
/// divided by. domainPlacement() maps it to the unit box: unit = (world - min) / side.
///
/// Distances: the shape is mapped to those unit coordinates and sampled by buildShapeSampler()
/// (DistanceField.h) at a level L: exact distances to the mesh (or polyline) on the nodes of a
/// narrow band of +-8 voxels at level L, of a band at L - 2, and of a dense box over all of
/// Omega at level min(L, 5) in 3D or min(L, 7) in 2D; between nodes the C1 quadratic B-spline
/// quasi-interpolant of the finest tier that covers the point. Near the shape the error is about
/// (h^2 / 8) |Laplacian d| (h = 2^-L Omega units, e.g. 2e-5 of the box for a sphere of radius
/// 0.3 at L = 8); away from it, in the coarse tiers, it is larger but the values stay continuous
/// and finite. Points outside the sampler's box (beyond Omega by more than 2.5 coarse voxels)
/// get the value at the nearest point of [0,1]^D plus the distance to it (a 1-Lipschitz
/// extension, positive outside the shape).
///
/// Units: world positions in, world distances out (unit distances / scale); negative inside.
/// In 2D the z of a query is ignored.
/// Thread-safety: signedDistance() may be called concurrently.
/// @see paper subsec:notation
#pragma once

#include <vdbmatch/geometry/FieldSampler.h>
#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/geometry/UnitBox.h>
#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>

#include <string>

namespace vdbmatch {
namespace eval {

/// World side length of Omega: the largest extent of field.worldBounds() over the first
/// field.dimension() axes.
double domainSize(const DeformationField& field);

/// The placement of Omega in the unit box: worldOrigin = worldBounds().min(), scale = 1 / side.
UnitBoxPlacement domainPlacement(const DeformationField& field);

/// The level of the deformation grid: round(log2(side / voxelSize)).
int deformationLevel(const DeformationField& field);

/// Largest distance level chosen automatically (memory and time of the band grows as 4^L in 3D).
constexpr int MAX_AUTO_DISTANCE_LEVEL_3D = 8;
constexpr int MAX_AUTO_DISTANCE_LEVEL_2D = 11;
/// Smallest distance level chosen automatically, so that coarse deformations are still measured
/// against accurate distances.
constexpr int MIN_AUTO_DISTANCE_LEVEL_3D = 7;
constexpr int MIN_AUTO_DISTANCE_LEVEL_2D = 9;

/// The distance level used when none is given: deformationLevel + 1, clamped to
/// [MIN_AUTO_DISTANCE_LEVEL_*, MAX_AUTO_DISTANCE_LEVEL_*] of the dimension.
int defaultDistanceLevel(int dim, int deformationLevel);

/// Checks that every point of a world shape lies in Omega (within a tolerance of 1e-9 of the
/// side, first D axes only).
/// @param what  names the shape in the message, e.g. "M1 (source)"
/// @throw openvdb::ValueError if a point lies outside
template <int D>
void checkShapeInDomain(const Surface<D>& worldSurface, const UnitBoxPlacement& omega,
                        const std::string& what);

/// Signed distance to a closed world shape, valid at any world point (file comment).
template <int D> class ShapeDistance
{
public:
    /// @param worldSurface  closed surface/curve in world units (checkSurface)
    /// @param omega         the placement of Omega (domainPlacement())
    /// @param level         sampler level L in [MIN_DISTANCE_LEVEL, MAX_DISTANCE_LEVEL]
    /// @throw openvdb::ValueError as buildShapeSampler
    ShapeDistance(const Surface<D>& worldSurface, const UnitBoxPlacement& omega, int level,
                  bool threaded = true);

    /// Signed distance at @a xWorld, world units, negative inside.
    double signedDistance(const openvdb::Vec3d& xWorld) const;
    /// Node spacing of the finest tier, world units.
    double voxelSize() const { return mVoxelSizeWorld; }
    int level() const { return mLevel; }

private:
    UnitBoxPlacement mOmega;
    typename FieldSampler<D>::ConstPtr mSampler;
    int mLevel = 0;
    double mVoxelSizeWorld = 0;
};

extern template class ShapeDistance<2>;
extern template class ShapeDistance<3>;

} // namespace eval
} // namespace vdbmatch
