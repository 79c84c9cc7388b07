/// @file VdbFileCheck.h
/// @brief Bounds check of the structure of a .vdb file before OpenVDB reads it.
///
/// OpenVDB's readers trust the lengths and counts stored in a file: a string length is used to
/// allocate before the bytes are read, and a length read from a truncated stream is an
/// uninitialised value (openvdb/util/Name.h readString). A .vdb truncated to 300 bytes made
/// `vdb_match match` grow to 5.1 GB before it failed (issue 10). checkVdbFileStructure() walks
/// the parts OpenVDB reads before any grid data, without allocating from file values:
/// - the header (magic number, format version, library version, grid-offsets flag, UUID);
/// - the file metadata (count, then name, type name and sized value of each item);
/// - each grid descriptor (unique name, type name, instance parent, grid/block/end offsets),
///   the grid's compression flags, metadata and transform type name;
/// - for trees of a known value type (float, double, int32, int64, vec3s/d/i): the root's tile
///   and child counts, and, for the standard 5_4_3 trees, every node below the root (masks,
///   the metadata, inactive values and selection mask of io::readCompressedValues, and the
///   size of each blosc/zip block, which io::bloscFromStream allocates before reading);
/// and checks that every length and count fits in the bytes that follow, that the offsets of
/// each grid are ordered and lie inside the file, and that a walked tree's topology and leaf
/// data end exactly at the grid's block and end offsets.
/// Files of format version 213 (2013) and later are accepted; bool, mask and point grids and
/// other tree configurations are checked down to their descriptors only.
#pragma once

#include <string>

namespace vdbmatch {

/// Checks the structure of the .vdb file at @a path (see the file comment).
/// @param path    file to check
/// @param where   starts every message and names the caller and the file, e.g.
///                "readLevelSet: file 'a.vdb'" (followed by " is truncated or corrupt: ...")
/// @throw openvdb::IoError starting with @a where if the file cannot be opened, is not a VDB
///        file, was written without grid offsets (an OpenVDB stream, not supported), or a
///        length, count or offset does not fit in the file (truncated or corrupt)
void checkVdbFileStructure(const std::string& path, const std::string& where);

} // namespace vdbmatch
