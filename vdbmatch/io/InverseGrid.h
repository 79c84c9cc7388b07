/// @file InverseGrid.h
/// @brief The inverse deformation phi^{-1} as an interchange grid: the displacement
///        phi^{-1}(y) - y at every node of phi's grid, evaluated exactly
///        (DeformationField::inverse).
///
/// Same layout, transform, vector type and name ("displacement") as the deformation grid
/// (DeformationIO.h), with the boolean metadata `is_inverse` set, so that a tool that reads
/// deformation.vdb reads inverse.vdb the same way. The node values are exact; between nodes,
/// the Kuhn (or trilinear) interpolation of the grid is an O(h^2) approximation of phi^{-1}
/// (phi^{-1} is piecewise linear on the *deformed* simplices, not on the voxels). For the exact
/// inverse between nodes, evaluate DeformationField::inverse on the forward grid (what
/// `vdb_match apply --inverse` does).
///
/// Determinism: each leaf is filled in a fixed order, the walk of each node starting from the
/// previous node's result, so the grid does not depend on the thread count.
#pragma once

#include <vdbmatch/io/DeformationField.h>

#include <openvdb/openvdb.h>
#include <openvdb/util/NullInterrupter.h>

#include <cstddef>

namespace vdbmatch {

/// Name of the boolean metadata that marks an inverse deformation grid.
constexpr const char* INVERSE_METADATA = "is_inverse";

/// Result of makeInverseGrid.
struct InverseGridResult
{
    openvdb::Vec3SGrid::Ptr grid; ///< null if interrupted
    std::size_t nodes = 0;        ///< nodes evaluated
    std::size_t failures = 0;     ///< nodes whose walk met det D phi <= 0 (value: last point)
    double maxResidual = 0;       ///< max |phi(phi^{-1}(y)) - y| over the nodes, world units
                                  ///< (InverseResult::residual: in the walk's last simplex)
};

/// phi^{-1}(y) - y at every active voxel of @a phi's grid (file comment).
/// @param threaded     use TBB (the result does not depend on it)
/// @param interrupter  checked once per leaf; if it fires the result has a null grid
InverseGridResult makeInverseGrid(const DeformationField& phi, bool threaded = true,
                                  openvdb::util::NullInterrupter* interrupter = nullptr);

} // namespace vdbmatch
