/// @file GridTransport.h
/// @brief Carrying an OpenVDB grid through a deformation: a level set as the surface it
///        describes, any other scalar or vector grid as a field pulled back through the map.
///
/// Directions (docs/apply.md has a picture). phi maps the source space to the target space.
/// - A **level set** (FloatGrid of class level set) describes a surface S: its zero level set
///   is extracted (extractSurface; extractCurve for a one-layer 2D slice), every vertex is moved
///   by phi (phi^{-1} with @a inverse), and the signed distance of the moved surface phi(S) is
///   rebuilt on the input's transform with the input's band width (levelSetFromSurface). Like a
///   mesh, the surface moves *with* the map.
/// - A **field** f (fog/density, colour, velocity; Float, Double, Vec3s or Vec3d grids of any
///   other class) is carried so that its values move with the points: the output g is
///   @f[ g(y) = f(\phi^{-1}(y)) \quad\text{(forward)}, \qquad g(x) = f(\phi(x)) \quad
///   \text{(inverse)}, @f]
///   evaluated at every output voxel centre with the exact inverse (DeformationField::inverse)
///   and trilinear sampling of f. Values are carried unchanged: a density is not divided by
///   det D phi (no mass conservation) and vectors are not rotated by D phi.
///   The output's active voxels are the images of the input's active voxels (voxel centres
///   mapped by phi, rounded to voxels and dilated by one voxel), kept where the trilinear
///   stencil of the pulled-back point touches an active input voxel.
/// The output has the input's name, class, transform and metadata (a 2D slice at layer k0 is
/// rebuilt at k = 0 with its transform pre-translated by k0 voxels, i.e. in the same world plane).
/// Points outside the deformation's domain Omega stay where they are (phi = Id there).
#pragma once

#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <cstddef>
#include <string>

namespace vdbmatch {

/// What transportGrid did.
struct GridTransportResult
{
    openvdb::GridBase::Ptr grid;     ///< the carried grid; null if interrupted
    bool levelSet = false;           ///< carried as a surface (else pulled back as a field)
    std::size_t points = 0;          ///< surface vertices moved, or output voxels evaluated
    std::size_t inverseFailures = 0; ///< inverse walks that did not end (DeformationField)
};

/// True if transportGrid accepts @a grid: a FloatGrid level set, or a Float, Double, Vec3s or
/// Vec3d grid.
bool isTransportableGrid(const openvdb::GridBase& grid);

/// Carries @a grid by phi (or phi^{-1} if @a inverse), as the file comment says.
/// @param threaded     use TBB (the result does not depend on it)
/// @param interrupter  checked once per leaf; if it fires the result's grid is null
/// @throw openvdb::TypeError naming the grid if its type is not supported
/// @throw openvdb::ValueError naming the grid if its transform is not linear with uniform
///        voxels, a level set has no zero crossing, a 2D slice is given to a 3D deformation, or
///        a 3D grid (active voxels in more than one layer) to a 2D deformation
GridTransportResult transportGrid(const openvdb::GridBase& grid, const DeformationField& phi,
                                  bool inverse, bool threaded = true,
                                  openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace vdbmatch
