/// @file DeformationField.h
/// @brief A deformation phi read back from a deformation grid (DeformationIO.h), evaluated exactly
///        as the piecewise-linear map it is: phi(x) = x + u(x) with u the Kuhn (Freudenthal)
///        piecewise-linear interpolant of the voxel values.
///
/// In index space p = worldToIndex(x) (a uniform scale and a translation of world space), the
/// voxel cell with origin o = floor(p) and local coordinates t = p - o in [0,1]^d is split into
/// d! Kuhn simplices exactly as the lattice cells of vdbmatch (SimplexLattice.h); the simplex
/// containing p visits the axes by decreasing t, with barycentric weights
/// 1 - t_{pi(1)}, t_{pi(1)} - t_{pi(2)}, ..., t_{pi(d)} on the path vertices. A grid written by
/// makeDeformationGrid at the lattice's finest level has a voxel at every lattice node, and every
/// lattice simplex is a union of voxel simplices, so this reproduces the computed phi exactly
/// (up to the single-precision storage of the values); no smoothing hides errors. Voxels without
/// an active value count as 0 (phi = Id outside Omega, where the grid stores nothing).
///
/// 2D grids (all active voxels at one k, DeformationIO.h) are evaluated in the plane of that
/// layer: the z of the query is ignored and the result keeps it.
///
/// Spaces: every position and displacement is in world units (the inputs' world space).
/// Thread-safety: const queries may be called concurrently.
/// @see paper sec:numerics
#pragma once

#include <openvdb/openvdb.h>

#include <string>

namespace vdbmatch {

class DeformationField
{
public:
    /// @param grid  a displacement grid (DeformationIO.h): linear transform with uniform voxels
    ///              and no rotation (a scale and a translation)
    /// @throw openvdb::ValueError if the grid is null, has no active voxel, or its transform is
    ///        not a uniform scale and translation
    explicit DeformationField(openvdb::Vec3SGrid::ConstPtr grid);

    /// Reads the displacement grid of a deformation file (readDeformation).
    /// @throw as readDeformation and the constructor
    static DeformationField read(const std::string& path);

    /// 2 for a one-layer grid, else 3.
    int dimension() const { return mDim; }
    const openvdb::Vec3SGrid& grid() const { return *mGrid; }
    /// World box of the active voxels (the domain Omega in world units).
    const openvdb::BBoxd& worldBounds() const { return mWorldBounds; }
    /// Voxel size in world units.
    double voxelSize() const { return mVoxelSize; }

    /// u(x), world units; 0 outside the active voxels.
    openvdb::Vec3d displacement(const openvdb::Vec3d& xWorld) const;
    /// phi(x) = x + u(x).
    openvdb::Vec3d apply(const openvdb::Vec3d& xWorld) const
    {
        return xWorld + displacement(xWorld);
    }
    /// det D phi on the Kuhn simplex of the voxel grid that contains x (1 outside the grid).
    double jacobianDeterminant(const openvdb::Vec3d& xWorld) const;

private:
    /// Index position, cell origin and the containing simplex's path (vertices, weights).
    void locate(const openvdb::Vec3d& xWorld, openvdb::Coord* vertices, double* weights,
                int* axes) const;

    openvdb::Vec3SGrid::ConstPtr mGrid;
    int mDim = 3;
    int mSliceK = 0;
    double mVoxelSize = 1;
    openvdb::BBoxd mWorldBounds;
};

} // namespace vdbmatch
