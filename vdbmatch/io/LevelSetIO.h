/// @file LevelSetIO.h
/// @brief Reading the input level sets of a matching problem from .vdb files, with the checks that
///        make a grid usable as a closed surface, and writing .vdb files atomically.
///
/// Conventions of an input level set (docs/cli.md, /work/shared/docs/interchange.md): a FloatGrid
/// of class "level set" holding a signed distance in world units, negative inside, with a narrow
/// band of active voxels around a closed zero level set; any linear transform with uniform voxel
/// size (scale, rotation, translation). Houdini names such grids "surface".
/// A 2D shape is a slice: a level set whose active voxels all have the same k (one layer in z);
/// its outer-layer check (checkInputLevelSet) then looks at the x and y faces only.
#pragma once

#include <openvdb/openvdb.h>

#include <string>

namespace vdbmatch {

/// Reads one signed-distance level set from a .vdb file.
/// @param path      file to read
/// @param gridName  name of the grid to read; if empty, the file must hold exactly one FloatGrid
/// @return the grid, checked with checkInputLevelSet()
/// @throw openvdb::IoError if the file is missing, unreadable, not a VDB file or corrupt
/// @throw openvdb::TypeError if the file has no FloatGrid, or the named grid is not a FloatGrid
/// @throw openvdb::ValueError if no grid has the given name, several FloatGrids exist and no
///        name was given (the message lists them), or checkInputLevelSet() fails
/// Thread-safety: may be called concurrently for different files.
openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName = "");

/// Smallest world length OpenVDB represents as a voxel: a linear transform needs a determinant
/// above 1e-15 (openvdb::math::ScaleMap: "Non-zero scale values required"), i.e. a uniform voxel
/// above 1e-5. Input level sets, and every grid match writes in world units, need voxels above it.
constexpr double MIN_WORLD_VOXEL_SIZE = 1e-5;
/// Largest input voxel size: distances and displacements are stored in single precision in world
/// units (largest float 3.4e38); 1e33 leaves room for shapes of 10^5 voxels across.
constexpr double MAX_WORLD_VOXEL_SIZE = 1e33;

/// Band half width (voxels) of the level sets made from densities by levelSetAtIsoValue().
constexpr double ISO_LEVEL_SET_HALF_WIDTH = 3.0;

/// The level set of the iso-surface {f = isoValue} of a density f (a fog volume, or any float
/// grid that is not a level set), inside where f > isoValue: f is negated and rebuilt as a signed
/// distance with openvdb::tools::levelSetRebuild (volumeToMesh at the iso value, then an exact
/// distance in a band of ISO_LEVEL_SET_HALF_WIDTH voxels on the same transform), then checked with
/// checkInputLevelSet(). A grid of class level set is only checked (and copied): isoValue applies
/// to densities.
/// @param context  names the grid in messages
/// @throw openvdb::ValueError if the transform is not linear with cubic voxels, a value is not
///        finite, the grid is empty or one voxel thick (2D), isoValue is not strictly between the
///        smallest and largest active values, or the result fails checkInputLevelSet()
openvdb::FloatGrid::Ptr levelSetAtIsoValue(const openvdb::FloatGrid& density, double isoValue,
                                           const std::string& context);

/// Reads a float grid as readLevelSet() selects it and returns levelSetAtIsoValue() of it.
/// @throw as readLevelSet() (except the level set checks of a density) and levelSetAtIsoValue()
openvdb::FloatGrid::Ptr readLevelSetAtIsoValue(const std::string& path, const std::string& gridName,
                                               double isoValue);

/// Checks that @a grid can be used as the signed distance of a closed surface:
/// - grid class GRID_LEVEL_SET (a fog volume, or a grid with every value in [0, 1], gets a
///   message that says to convert it with an iso value: readLevelSetAtIsoValue, --iso-value);
/// - a linear transform with uniform voxel size (a similarity: no shear or non-uniform scale),
///   in (MIN_WORLD_VOXEL_SIZE, MAX_WORLD_VOXEL_SIZE];
/// - finite values everywhere (active, inactive, tiles, background) and a positive background;
/// - no active tiles, at least one active voxel, and a zero crossing (active values of both
///   signs);
/// - the outermost layer of active voxels (those on the faces of the active-voxel bounding box)
///   lies outside the surface, at least half a voxel away (d >= h/2). This cheaply detects open
///   or clipped surfaces, whose zero crossing reaches the edge of the band, and flipped signs.
/// @param grid     the grid
/// @param context  names the grid in messages, e.g. "file 'a.vdb', grid 'surface'"
/// @throw openvdb::ValueError naming the first failed check
void checkInputLevelSet(const openvdb::FloatGrid& grid, const std::string& context);

/// Writes @a grids and @a fileMeta to @a path without ever leaving a partial file there: writes
/// a temporary file in the same directory, flushes it to disk and renames it over @a path.
/// @throw openvdb::IoError if the temporary file cannot be written or renamed (it is removed)
void writeGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids,
                          const openvdb::MetaMap& fileMeta);

} // namespace vdbmatch
