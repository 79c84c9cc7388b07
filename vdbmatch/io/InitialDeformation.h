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
///
/// **Warm starts** (`vdb_match match --warm-start`, InitPlacement::Carried): the map of another
/// pair, e.g. frames k-1 -> k of a sequence as the start of k -> k+1. phi is a map of world space
/// (the identity outside the earlier Omega), so it is carried into the current placement as
/// x -> s' (phi(x') - x') with x' the world point of x: exact wherever the current Omega lies in
/// the earlier one, and Id beyond. D phi is unchanged by the change of placement (a similarity),
/// so the Lipschitz bound carries over. match() sets the boundary nodes to 0 and checks the start
/// for folds.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Match.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <openvdb/openvdb.h>

#include <memory>
#include <string>

namespace vdbmatch {

/// How the grid's placement must relate to the current inputs'.
enum class InitPlacement {
    Same,   ///< the same inputs (--init): the placements must agree
    Carried ///< another pair (--warm-start): any placement, the map carried through world space
};

/// An earlier result read for --init or --warm-start.
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
///        and how to fix it; InitPlacement::Same only)
InitialDeformation readInitialDeformation(const std::string& path,
                                          const UnitBoxPlacement& placement, int dim,
                                          InitPlacement mode = InitPlacement::Same);

/// As readInitialDeformation, from a grid in memory; @a what names it in messages.
InitialDeformation initialDeformationFromGrid(openvdb::Vec3SGrid::ConstPtr grid,
                                              const UnitBoxPlacement& placement, int dim,
                                              const std::string& what,
                                              InitPlacement mode = InitPlacement::Same);

} // namespace vdbmatch
