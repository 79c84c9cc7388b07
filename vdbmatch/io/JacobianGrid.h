/// @file JacobianGrid.h
/// @brief det D phi as an interchange grid: one value per voxel cell of the deformation grid, the
///        volume ratio |phi(cell)| / |cell| (the mean of det D phi over the cell's d! Kuhn
///        simplices), or its logarithm.
///
/// Layout: an openvdb::FloatGrid named JACOBIAN_GRID_NAME ("det_jacobian") or
/// LOG_JACOBIAN_GRID_NAME ("log_det_jacobian"), class GRID_UNKNOWN, background
/// 1 (0 for the logarithm: phi = Id outside Omega), no tiles; voxel ijk holds the cell whose
/// lowest corner is node ijk of the deformation grid, and the transform is the deformation's
/// shifted by half a voxel, so that a voxel centre is the cell centre (what Houdini's
/// volumesample and Blender's Sample Volume interpolate from). 2D: one layer, cells of the plane.
/// Metadata `vdbmatch_det_min` / `vdbmatch_det_max` hold the extremes of det D phi over the
/// simplices (eval::jacobianStats, `vdb_match consistency`), which bound the cell means.
#pragma once

#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

namespace vdbmatch {

constexpr const char* JACOBIAN_GRID_NAME = "det_jacobian";
constexpr const char* LOG_JACOBIAN_GRID_NAME = "log_det_jacobian";

/// The volume-ratio grid of @a phi (file comment).
/// @param logarithm    store log(|phi(cell)| / |cell|) instead
/// @param threaded     use TBB (the result does not depend on it)
/// @param interrupter  checked once per row of cells; if it fires the result is null
/// @throw openvdb::ValueError if @a logarithm and a cell's volume ratio is not positive (phi
///        folds)
openvdb::FloatGrid::Ptr makeJacobianGrid(const DeformationField& phi, bool logarithm = false,
                                         bool threaded = true,
                                         openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace vdbmatch
