/// @file PlyWriter.h
/// @brief Writing a triangle mesh with optional per-vertex colours as a PLY file (Stanford
///        polygon format), readable by Blender, MeshLab and ParaView.
///
/// Format: header "ply", "format binary_little_endian 1.0" or "format ascii 1.0", optional
/// comment lines, then
///   element vertex N: property float x, y, z [, property uchar red, green, blue]
///   element face M:   property list uchar int vertex_indices
/// Coordinates are written as 32-bit floats in the caller's world units; colours as sRGB bytes.
/// Binary values are little endian whatever the host.
#pragma once

#include <openvdb/Types.h>

#include <array>
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace vdbmatch {

enum class PlyFormat { BinaryLittleEndian, Ascii };

/// Writes the mesh to @a os (opened in binary mode for PlyFormat::BinaryLittleEndian).
/// @param colors   one sRGB colour per point, or empty for no colour properties
/// @param comment  written as "comment ..." header lines, one per line of the text (may be empty)
/// @throw openvdb::ValueError if colors is neither empty nor one per point, a triangle index is
///        out of range, or a point is not finite
/// @throw openvdb::IoError if the stream fails
void writePly(std::ostream& os, const std::vector<openvdb::Vec3d>& points,
              const std::vector<std::array<std::int32_t, 3>>& triangles,
              const std::vector<std::array<std::uint8_t, 3>>& colors,
              PlyFormat format = PlyFormat::BinaryLittleEndian, const std::string& comment = "");

} // namespace vdbmatch
