/// @file MeshIO.h
/// @brief Reading and writing explicit shapes: triangle meshes (.obj, .ply, .stl) for 3D and
///        closed polylines (.polyline) for 2D.
///
/// Everything is in world units, the units of the file. Readers return a surface that passed
/// checkSurface() (closed, finite, not degenerate); polygons are fan-triangulated, and elements
/// that repeat a vertex (zero area) are dropped.
///
/// Polyline format (`.polyline`, also `.txt`), one closed curve per block of lines:
/// @code
/// # comment (from '#' to the end of the line)
/// x0 y0
/// x1 y1
/// x2 y2          <- the last point connects back to the first, which is not repeated
///
/// x0 y0          <- a blank line starts the next curve
/// ...
/// @endcode
/// Each curve has at least 3 points. Orientation is free (signs come from crossing parity).
#pragma once

#include <vdbmatch/geometry/Surface.h>

#include <ostream>
#include <string>

namespace vdbmatch {

/// Reads a closed triangle mesh, by extension (case-insensitive):
/// - .obj: `v x y z` (optionally followed by `w`, or a vertex colour `r g b [a]`, ignored) and
///   `f i j k ...` lines (1-based or negative relative indices, `i/t/n`
///   forms accepted); polygons are fan-triangulated; other lines (vt, vn, g, o, s, usemtl ...)
///   are ignored;
/// - .ply: ascii, binary_little_endian and binary_big_endian; the vertex element's x, y, z
///   (any scalar type) and the face element's vertex_indices / vertex_index list (any integer
///   count and index types); other elements and properties are skipped;
/// - .stl: ascii or binary (detected by size); vertices with identical coordinates are merged.
/// @throw openvdb::IoError if the file is missing or cannot be read
/// @throw openvdb::ValueError naming the file if the extension is unknown, the content is
///        malformed or truncated, or the mesh fails checkSurface()
Surface<3> readMesh(const std::string& path);

/// Reads closed curves in the polyline format above (.polyline or .txt).
/// @throw openvdb::IoError if the file is missing or cannot be read
/// @throw openvdb::ValueError naming the file and line if the content is malformed, a curve has
///        fewer than 3 points, or the result fails checkSurface()
Surface<2> readPolyline(const std::string& path);

/// Writes a triangle mesh as OBJ (`v x y z` with round-trip precision, `f a b c` 1-based).
void writeObj(std::ostream& out, const Surface<3>& surface);

/// Writes curves as OBJ lines: `v x y 0` and `l a b` (1-based), one per segment.
void writeObj(std::ostream& out, const Surface<2>& surface);

/// Writes curves in the polyline format, one block per closed curve, each curve following its
/// segments (so orientation is kept where consistent).
/// @throw openvdb::ValueError if the surface is not a set of closed curves (checkSurface)
void writePolyline(std::ostream& out, const Surface<2>& surface);

} // namespace vdbmatch
