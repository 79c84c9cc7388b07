/// @file DeformationIO.h
/// @brief The deformation phi as an interchange grid: the displacement phi(x) - x sampled on the
///        nodes of a regular grid of Omega, in the inputs' world space, as a single-precision
///        vector grid that Houdini, Blender and pyopenvdb read as it is; and reading it back.
///
/// Layout of the grid (docs/cli.md, /work/shared/docs/interchange.md):
/// - an openvdb::Vec3SGrid named DEFORMATION_GRID_NAME ("displacement"), vector type
///   contravariant relative, background 0, no tiles;
/// - voxel ijk is the node ijk H of Omega at the output level L (H = 2^-L, i in [0, 2^L]^d), i.e.
///   the index-to-world transform is the placement's inverse: a uniform scale H / s and the
///   translation worldOrigin (s, worldOrigin: UnitBoxPlacement). In 2D only k = 0 is used and
///   the z of that plane is the world z of the inputs' plane;
/// - value = phi(x) - x in world units (z = 0 in 2D). Outside Omega phi = Id: the value there
///   is the background 0.
/// At the finest level of the lattice (the default) every node of the lattice is a voxel and
/// phi is linear on the Kuhn simplices of the voxels (coarse lattice cells are unions of them),
/// so the Kuhn piecewise-linear interpolation of the grid (multiscale::PiecewiseLinearInterpolator
/// logic) reproduces phi exactly; trilinear sampling (what DCC tools do) is second-order close.
/// Every value is finite.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/UnitBox.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/openvdb.h>

#include <string>

namespace vdbmatch {

/// Name of the displacement grid in deformation files.
constexpr const char* DEFORMATION_GRID_NAME = "displacement";

/// Samples phi - Id of the lattice's piecewise-linear displacement at every node of Omega at
/// @a outputLevel and returns it as a world-space grid (layout in the file comment).
/// @param lattice      the lattice and @param u its nodal displacement (D x nodeCount, Omega)
/// @param placement    world <-> Omega map of the inputs
/// @param outputLevel  node spacing 2^-outputLevel; <= 0 selects lattice.level()
/// @param threaded     use TBB (the result does not depend on it)
/// @throw openvdb::ValueError if u has the wrong size, outputLevel > lattice.level() or is
///        above 12, or a value is not finite
template <int D>
openvdb::Vec3SGrid::Ptr
makeDeformationGrid(const SimplexLattice<D>& lattice, const NodeVectors<D>& u,
                    const UnitBoxPlacement& placement, int outputLevel = 0, bool threaded = true);

/// Reads the displacement grid of a deformation file.
/// @throw openvdb::IoError if the file cannot be read, or is truncated or corrupt (see
///        checkVdbFileStructure)
/// @throw openvdb::ValueError if it holds no Vec3SGrid named "displacement", the transform is
///        not linear with uniform voxels, or a value is not finite
openvdb::Vec3SGrid::Ptr readDeformation(const std::string& path);

} // namespace vdbmatch
