/// @file InitialDeformation.h
/// @brief An earlier result of match (its deformation.vdb) as the start of a new descent
///        (`vdb_match match --init`): the grid's placement checked against the current inputs',
///        the levels of the earlier run, and phi - Id in Omega units at any point of Omega.
///
/// A deformation grid (DeformationIO.h) stores u = phi - Id in world units on the nodes of
/// Omega at its level L: voxel ijk is the node ijk 2^-L, so its index-to-world transform is a
/// uniform scale 2^-L / s and the translation worldOrigin of the placement that produced it
/// (unit = s (world - worldOrigin)). The current inputs, placed with the current margin, must
/// give the same placement, else the earlier phi would be read in another frame: the check
/// compares both to 1e-5 of a node spacing. The displacement at x in Omega is the exact Kuhn
/// piecewise-linear interpolation of the grid (DeformationField), times s.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Match.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <openvdb/openvdb.h>

#include <memory>
#include <string>

namespace vdbmatch {

/// An earlier result read for --init.
struct InitialDeformation
{
    std::shared_ptr<const InitialDisplacement> start; ///< for MatchOptions::initial
    int gridLevel = 0;                                ///< node spacing 2^-gridLevel of the grid
    int firstLevel = 0;       ///< the earlier run's first level (vdbmatch_levels), else gridLevel
    int finestLevel = 0;      ///< the earlier run's finest level (vdbmatch_levels), else gridLevel
    bool interrupted = false; ///< the earlier run was interrupted (is_interrupted)

    /// The level a run from this result starts at: the next finer one, or the finest again if
    /// that level was interrupted (it resumes).
    int nextLevel() const { return interrupted ? finestLevel : finestLevel + 1; }
};

/// Reads the deformation grid of @a path (readDeformation) for the inputs placed by @a placement.
/// @param dim  the inputs' dimension
/// @throw openvdb::IoError as readDeformation
/// @throw openvdb::ValueError if the grid is not a deformation grid of dimension @a dim on the
///        nodes of Omega, or its placement differs from @a placement (the message says which
///        and how to fix it)
InitialDeformation readInitialDeformation(const std::string& path,
                                          const UnitBoxPlacement& placement, int dim);

/// As readInitialDeformation, from a grid in memory; @a what names it in messages.
InitialDeformation initialDeformationFromGrid(openvdb::Vec3SGrid::ConstPtr grid,
                                              const UnitBoxPlacement& placement, int dim,
                                              const std::string& what);

} // namespace vdbmatch
