/// @file SurfaceExtraction.h
/// @brief The zero level set of an input level set as an explicit surface: triangles from a 3D
///        grid, closed curves from a 2D "slice" grid.
///
/// A 2D input is a FloatGrid level set whose active voxels all lie in one layer k = k0 (a
/// "slice"); its curve is the zero level set of the bilinear interpolant on that layer. Grid
/// values are world distances, negative inside; a narrow band of a few voxels (Houdini's 3) is
/// enough, since the zero crossings lie between voxels of opposite sign inside the band, and
/// inactive values carry the sign of the background (+ outside, - inside).
///
/// Output space: world units of the grid (its transform applied to fractional index positions).
/// For a slice, x and y of the world positions are returned (the transform should map the layer
/// to a plane z = const, e.g. scale + translation).
#pragma once

#include <vdbmatch/geometry/Surface.h>

#include <openvdb/openvdb.h>

namespace vdbmatch {

/// Triangle mesh of the zero isosurface: tools::volumeToMesh (isovalue 0, adaptivity 0), quads
/// split into two triangles (0,1,2), (0,2,3). World space of the grid.
/// @throw openvdb::ValueError naming the grid if the zero level set is empty
Surface<3> extractSurface(const openvdb::FloatGrid& levelSet);

/// True if the grid has at least one active voxel, no active tiles, and all active voxels share
/// the same k index.
bool isSlice(const openvdb::FloatGrid& grid);

/// Closed curves of the zero level set of a slice grid by marching squares on its layer.
/// - Zero crossings are interpolated linearly along cell edges; a node is inside iff its value
///   is < 0 (a node value of exactly 0 counts as outside).
/// - Segments are oriented with the inside on their left in index space (counter-clockwise
///   around inside regions when the transform preserves orientation).
/// - Saddle cells (diagonal corners of equal sign) are resolved by the asymptotic decider: the
///   inside corners are joined iff the bilinear interpolant is negative at its saddle point.
///   The result is deterministic and closed: every vertex is used by exactly two segments.
/// Vertices are shared between the two cells of an edge; they are numbered in cell order
/// (y-major, then x), so the result does not depend on the tree layout.
/// @throw openvdb::ValueError naming the grid if it is not a slice or the curve is empty
Surface<2> extractCurve(const openvdb::FloatGrid& slice);

} // namespace vdbmatch
