/// @file UnitBox.h
/// @brief Placement of the two input shapes in the computational domain Omega = (0,1)^3 by one
///        common similarity transform, and resampling of an input level set as a signed distance
///        grid in Omega coordinates.
///
/// The paper works in a bounded domain Omega with the Dirichlet condition phi = Id on its
/// boundary (eq:biSobolevDir); vdbmatch uses Omega = (0,1)^d. The shapes must therefore sit well
/// inside Omega: the union of the world bounding boxes of both zero level sets is mapped by
/// @f[ x_\mathrm{unit} = s\,(x_\mathrm{world} - o) @f]
/// so that its largest side becomes 1 - 2 margin and its centre lands at (1/2, 1/2, 1/2). The
/// same map is used for both shapes, so their relative position and size are kept.
///
/// Spaces and units: "world" is the world space of the input grids (any linear transform with
/// cubic voxels); "unit" is Omega. Distances scale by s. Signed distances are negative inside.
/// In 2D the shapes are curves in the plane z = 0: their box is flat in z, the placement scales
/// by the largest of the x and y sides, and only the x and y coordinates are used (see
/// Surface.h, transformed()).
/// @see paper eq:biSobolevDir, sec:numerics
#pragma once

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

namespace vdbmatch {

template <int D> struct Surface;

/// Default margin of the placement (Omega units, on every side of the union box).
/// @note The paper gives no value; 0.2 leaves room for the narrow band and for the deformation
/// between the shapes and the Dirichlet boundary.
constexpr double DEFAULT_UNIT_BOX_MARGIN = 0.2;

/// Nodes around [0, 2^level]^3 on each side on which resampled grids must hold distances (the
/// stencils of the shape fields reach beyond the boundary of Omega).
constexpr int UNIT_BOX_NODE_PADDING = 3;

/// One similarity transform world -> Omega for both shapes: unit = scale * (world - worldOrigin).
struct UnitBoxPlacement
{
    openvdb::Vec3d worldOrigin{0.0};         ///< world point mapped to the origin of Omega
    double scale = 1.0;                      ///< Omega length per world length
    double margin = DEFAULT_UNIT_BOX_MARGIN; ///< margin used, Omega units
    openvdb::BBoxd worldBox;                 ///< the world box that was placed

    openvdb::Vec3d toUnit(const openvdb::Vec3d& world) const
    {
        return (world - worldOrigin) * scale;
    }
    openvdb::Vec3d toWorld(const openvdb::Vec3d& unit) const { return unit / scale + worldOrigin; }
    double toUnitLength(double worldLength) const { return worldLength * scale; }
    double toWorldLength(double unitLength) const { return unitLength / scale; }

    /// The placement that maps @a worldBox into [margin, 1 - margin]^3: its largest side becomes
    /// 1 - 2 margin, its centre (1/2, 1/2, 1/2). A box flat along some axes (a 2D box has
    /// min z = max z) is accepted.
    /// @throw openvdb::ValueError if the box is empty (min > max on an axis), degenerate
    /// (largest side 0) or not finite,
    /// or margin is not in [0, 0.5).
    static UnitBoxPlacement fromWorldBox(const openvdb::BBoxd& worldBox,
                                         double margin = DEFAULT_UNIT_BOX_MARGIN);
};

/// World bounding box of the zero level set of @a levelSet: the box of the centres of the active
/// voxels with |d| <= h (h = voxel size, world units), widened by sqrt(3)/2 h on every side so
/// that it contains the surface (at most about h too large per side). Works for any linear
/// transform.
/// @throw openvdb::ValueError if no active voxel has |d| <= h.
openvdb::BBoxd zeroLevelSetWorldBox(const openvdb::FloatGrid& levelSet);

/// The common placement of two shapes: fromWorldBox of the union of their zeroLevelSetWorldBox.
/// @throw openvdb::ValueError as zeroLevelSetWorldBox and fromWorldBox
UnitBoxPlacement placeInUnitBox(const openvdb::FloatGrid& source, const openvdb::FloatGrid& target,
                                double margin = DEFAULT_UNIT_BOX_MARGIN);

/// The common placement of two explicit shapes (world units): fromWorldBox of the union of
/// their point bounding boxes (2D: z = 0, so the union box is mapped into
/// [margin, 1 - margin]^2, centred at (1/2, 1/2)).
/// @throw openvdb::ValueError if a surface has no points, or as fromWorldBox
template <int D>
UnitBoxPlacement placeInUnitBox(const Surface<D>& source, const Surface<D>& target,
                                double margin = DEFAULT_UNIT_BOX_MARGIN);

/// Smallest band width accepted by resampleToUnitBox, voxels (OpenVDB's level set half width).
constexpr double MIN_RESAMPLE_BAND_VOXELS = 3.0;

/// Resamples a level set as a signed distance grid in Omega coordinates.
///
/// Method: the zero isosurface of @a levelSet is extracted as quads and triangles
/// (tools::volumeToMesh, world space) and its vertices are mapped to Omega with @a placement.
/// The distance to this polygon mesh is computed in a narrow band by tools::meshToVolume (the
/// sign comes from a flood fill of the exterior, so the orientation of the polygons does not
/// matter), then extended to every node of the box
/// [-UNIT_BOX_NODE_PADDING, 2^level + UNIT_BOX_NODE_PADDING]^3 by closest-polygon propagation
/// (each new voxel takes the nearest of the polygons closest to its 26 neighbours, as
/// meshToVolume does to widen its band), restricted to that box so that the cost is
/// proportional to its volume. The input may be an exact distance or a narrow band of a few
/// voxels (e.g. from Houdini), with any voxel size and linear transform; the result is the
/// distance to the mesh approximation of the surface (accurate to a fraction of an input voxel).
///
/// @param levelSet          input level set, world units (see checkInputLevelSet)
/// @param placement         world -> Omega map
/// @param level             output voxel size h = 2^-level, level in [1, 12]
/// @param bandWidthVoxels   the result is also a true distance wherever |d| <= band * h
///                          (outside the node box too); >= MIN_RESAMPLE_BAND_VOXELS
/// @param interrupter       optional; if it interrupts, the result is nullptr
/// @return a FloatGrid of class level set named "surface" with the transform ijk -> ijk h
///         (voxel (i,j,k) at (i,j,k) h in Omega, no offset), negative inside, active (a true
///         distance) on every node of the box and wherever |d| <= band * h, background
///         max(band * h, largest |d| in the box), no active tiles; it passes
///         tools::checkLevelSet checks 1-8.
/// @throw openvdb::ValueError if level or band is out of range, the surface is empty, or the
///        placed surface does not meet the node box.
openvdb::FloatGrid::Ptr resampleToUnitBox(const openvdb::FloatGrid& levelSet,
                                          const UnitBoxPlacement& placement, int level,
                                          double bandWidthVoxels = MIN_RESAMPLE_BAND_VOXELS,
                                          openvdb::util::NullInterrupter* interrupter = nullptr);

/// True if every node of [-padding, 2^level + padding]^3 is an active voxel of @a grid.
bool coversUnitBoxNodes(const openvdb::FloatGrid& grid, int level,
                        int padding = UNIT_BOX_NODE_PADDING);

} // namespace vdbmatch
