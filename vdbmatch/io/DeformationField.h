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
/// **Exact inverse.** u is extended by 0 beyond the active voxels, so phi is a piecewise-linear
/// map of all of R^d that is the identity outside Omega; with det D phi > 0 on every simplex it is
/// a bijection (a proper local homeomorphism that is the identity near infinity). inverse(y)
/// finds the x with phi(x) = y by tracing the straight segment from phi(x0) to y through the
/// deformed simplices (x0 an initial guess): in the simplex T containing the current point x,
/// whose image is q = phi(x), the preimage of the segment [q, y] is the straight segment
/// x + s A_T^{-1}(y - q), s in [0, 1], A_T = D phi on T. If it leaves T before s = 1 the walk
/// moves to the exit point and continues in the next simplex along the same image segment; the
/// image of the walk is the segment [phi(x0), y] itself, so it crosses each deformed simplex at
/// most once and ends in the simplex containing phi^{-1}(y), where the affine inverse is exact.
/// No iteration to a tolerance is involved: phi(inverse(y)) = y to rounding error.
///
/// Spaces: every position and displacement is in world units (the inputs' world space).
/// Thread-safety: const queries may be called concurrently.
/// @see paper sec:numerics
#pragma once

#include <openvdb/openvdb.h>

#include <cstddef>
#include <string>
#include <vector>

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
    /// 2D: the index k of the plane the grid's voxels lie in (0 in 3D).
    int sliceIndex() const { return mSliceK; }
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
    /// D phi on the Kuhn simplex that contains x (the identity outside the grid; in 2D the third
    /// row and column are those of the identity). On a face between simplices, one of them.
    openvdb::Mat3d jacobian(const openvdb::Vec3d& xWorld) const;

    /// det D phi on the d! Kuhn simplices of the voxel cell whose lowest corner is the voxel
    /// @a cell (index space), in the order of std::next_permutation over the axes.
    /// @param dets  room for d! values
    /// @return d! (2 or 6)
    int cellDeterminants(const openvdb::Coord& cell, double* dets) const;
    /// The same from the displacements of the cell's corners, in index units (voxel value /
    /// voxelSize), corner c at cell + bit a of c along axis a (2^d of them): for callers that
    /// read a block of corners at once.
    static int cellDeterminants(int dimension, const openvdb::Vec3d* corners, double* dets);

    /// Result of an inverse evaluation.
    struct InverseResult
    {
        openvdb::Vec3d x;  ///< phi^{-1}(y), world units
        int simplices = 0; ///< simplices visited by the walk
        bool found = true; ///< false: the walk met a simplex with det D phi <= 0 or ran out
                           ///< of steps (x is then the last point reached)
        /// |phi(x) - y| with phi the affine map of the simplex where the walk ended (world
        /// units): rounding error only. (x can lie outside that simplex by the walk's nudge,
        /// 1e-9 voxel, where the map of the next simplex differs by that times the jump of
        /// D phi.) Computed at no cost, unlike a separate |apply(x) - y|.
        double residual = 0;
        /// D phi^{-1} at y: the inverse of D phi on the simplex where the walk ended (the
        /// identity if it did not end). x + J (y' - y) is a first-order guess for phi^{-1}(y').
        openvdb::Mat3d jacobian = openvdb::Mat3d::identity();
    };
    /// Exact phi^{-1}(y) (file comment), starting from the guess @a guessWorld (the fixed point
    /// iterate x = y - u(x) if none is given). Outside Omega, phi^{-1}(y) = y.
    InverseResult inverse(const openvdb::Vec3d& yWorld) const;
    InverseResult inverse(const openvdb::Vec3d& yWorld, const openvdb::Vec3d& guessWorld) const;

    /// Moves every point by phi (or by phi^{-1} if @a inverse), in parallel if @a threaded; the
    /// result does not depend on the thread count.
    /// @return the number of points whose inverse walk did not end (found == false); 0 for phi
    std::size_t mapPoints(std::vector<openvdb::Vec3d>& pointsWorld, bool inverse,
                          bool threaded = true) const;
    /// The same on @a count points stored contiguously (e.g. an (n, 3) array of doubles).
    std::size_t mapPoints(openvdb::Vec3d* pointsWorld, std::size_t count, bool inverse,
                          bool threaded = true) const;

    /// Unregistered accessor of the displacement tree (one per thread; cheap to make).
    using Accessor = openvdb::tree::ValueAccessor<const openvdb::Vec3STree, /*IsSafe=*/false>;

    /// The queries above through an accessor kept between calls, for many nearby points on one
    /// thread (the inverse grid, point sets): its cached tree path makes the lookups of
    /// neighbouring points cheap. The same results as the field's own queries, bit for bit.
    /// Not thread-safe; the field must outlive it.
    class Cursor
    {
    public:
        explicit Cursor(const DeformationField& field) : mField(&field), mAcc(field.grid().tree())
        {
        }
        openvdb::Vec3d displacement(const openvdb::Vec3d& xWorld)
        {
            return mField->displacement(xWorld, mAcc);
        }
        openvdb::Vec3d apply(const openvdb::Vec3d& xWorld) { return xWorld + displacement(xWorld); }
        InverseResult inverse(const openvdb::Vec3d& yWorld)
        {
            return mField->inverse(yWorld, mAcc);
        }
        InverseResult inverse(const openvdb::Vec3d& yWorld, const openvdb::Vec3d& guessWorld)
        {
            return mField->inverse(yWorld, guessWorld, mAcc);
        }

    private:
        const DeformationField* mField;
        Accessor mAcc;
    };

private:
    openvdb::Vec3d displacement(const openvdb::Vec3d& xWorld, Accessor& acc) const;
    InverseResult inverse(const openvdb::Vec3d& yWorld, Accessor& acc) const;
    InverseResult inverse(const openvdb::Vec3d& yWorld, const openvdb::Vec3d& guessWorld,
                          Accessor& acc) const;

    /// Index position, cell origin and the containing simplex's path (vertices, weights).
    void locate(const openvdb::Vec3d& xWorld, openvdb::Coord* vertices, double* weights,
                int* axes) const;
    /// The same in index space.
    void locateIndex(const openvdb::Vec3d& p, openvdb::Coord* vertices, double* weights,
                     int* axes) const;
    /// The walk of inverse(), in index space.
    InverseResult inverseIndex(const openvdb::Vec3d& y, openvdb::Vec3d x, Accessor& acc) const;

    openvdb::Vec3SGrid::ConstPtr mGrid;
    int mDim = 3;
    int mSliceK = 0;
    double mVoxelSize = 1;
    openvdb::BBoxd mWorldBounds;
};

} // namespace vdbmatch
