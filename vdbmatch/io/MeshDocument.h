/// @file MeshDocument.h
/// @brief A mesh file (.obj, .ply, .stl) kept whole, so that its vertex positions and normals
///        can be overwritten and the file written back with everything else unchanged.
///
/// The document holds the bytes of the file and, for every coordinate it exposes, where that
/// coordinate is stored (a token of the text, or a float/double in the binary data). write()
/// copies the original bytes and replaces only the coordinates whose value changed; an
/// unmodified document is written back byte for byte. This is what a "rest position" setup in a
/// DCC (Houdini, Blender) needs: same vertex order, same faces, attributes, groups, materials.
///
/// Positions and normals are in the units of the file (world units); nothing is merged,
/// reordered or triangulated. The class knows nothing about deformations.
///
/// Formats:
/// - OBJ: `v x y z [extra tokens...]` and `vn x y z` lines are the positions and normals; every
///   other line (comments, vt, f, l, g, o, s, usemtl, mtllib ...), extra tokens of a v line
///   (`w`, vertex colours), line endings (LF or CRLF) and blank lines are kept verbatim.
/// - PLY (ascii, binary_little_endian, binary_big_endian): the header and every element are
///   kept; the vertex element's x, y, z (float or double) and, when all three are present as
///   float or double, nx, ny, nz are the positions and normals, rewritten in their declared type.
/// - STL (ascii or binary, detected as readMesh does): positions are the facet corners (3 per
///   facet, not merged), normals the facet normals; the binary header and each facet's 2-byte
///   attribute, and the ascii solid name, are kept.
#pragma once

#include <openvdb/Types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {

/// A mesh file read whole, with editable vertex positions and normals.
/// Not thread-safe for concurrent modification; const members may be called concurrently.
class MeshDocument
{
public:
    enum class Format { Obj, Ply, Stl };

    /// Reads a .obj, .ply or .stl file (extension case-insensitive).
    /// @throw openvdb::IoError if the file is missing, a directory or unreadable
    /// @throw openvdb::ValueError naming the file (and the line, for text) if the extension is
    ///        unknown, the file is empty, the content is malformed or truncated (a PLY element
    ///        count larger than the data can hold included), a face refers to a missing vertex
    ///        or normal (OBJ), a PLY vertex lacks x, y or z or stores them in a type other than
    ///        float or double, or a position is not finite
    static MeshDocument read(const std::string& path);

    Format format() const { return mFormat; }
    /// True for binary PLY and binary STL.
    bool isBinary() const { return mEncoding != Encoding::Text; }

    /// Number of positions: OBJ `v` lines, PLY vertices, STL facets x 3.
    std::size_t vertexCount() const { return mPositions.size(); }
    /// Polygons as stored: OBJ `f` lines, PLY face instances, STL facets (quads count once).
    std::size_t faceCount() const { return mFaceCount; }

    /// Positions in file order (STL: one per facet corner, 3 per facet), world units. Overwrite
    /// the values; do not resize the vector (write() checks).
    std::vector<openvdb::Vec3d>& positions() { return mPositions; }
    const std::vector<openvdb::Vec3d>& positions() const { return mPositions; }

    /// Normals stored in the file, in file order: OBJ `vn` entries, PLY vertex nx/ny/nz (one per
    /// vertex), STL facet normals (one per facet). Empty if the file has none. Written as given
    /// (not renormalised). Non-finite normals are accepted on reading.
    std::vector<openvdb::Vec3d>& normals() { return mNormals; }
    const std::vector<openvdb::Vec3d>& normals() const { return mNormals; }

    /// For each normal, the ORIGINAL position where it applies: OBJ: the position of the first
    /// vertex that a face (`f`) pairs with that `vn`, or the origin if no face uses it (see
    /// isNormalUsed()); PLY: the vertex's own position; STL: the facet's centroid.
    const std::vector<openvdb::Vec3d>& normalAnchors() const { return mNormalAnchors; }
    /// False only for an OBJ `vn` that no face refers to (its anchor is the origin).
    bool isNormalUsed(std::size_t i) const { return mNormalUsed.at(i) != 0; }

    /// Appends a per-vertex scalar property: in PLY only, a `property float NAME` line after the
    /// vertex element's last property and one value per vertex at the end of each vertex row,
    /// in the file's encoding. Properties are appended in call order.
    /// @param name    a PLY identifier ([A-Za-z_][A-Za-z0-9_]*) not already a vertex property
    /// @param values  one finite value per vertex (size vertexCount())
    /// @throw openvdb::ValueError naming the file if the document is not PLY, the name is invalid
    ///        or already present, the size is wrong or a value is not finite
    void addVertexProperty(const std::string& name, std::vector<float> values);

    /// The file as write() would store it.
    /// @throw openvdb::ValueError if positions() or normals() were resized, or a changed value
    ///        is not finite (or, for a float property, overflows float)
    std::string render() const;

    /// Writes the document in the format and encoding it was read in, atomically (no partial
    /// file is ever left at @a path; see writeFileAtomically). Unchanged values keep their
    /// original text or bytes; changed ones are written with round-trip precision (the
    /// shortest text that reads back the same double, or float for an ascii PLY float).
    /// @throw openvdb::ValueError as render()
    /// @throw openvdb::IoError naming @a path if it cannot be written
    void write(const std::string& path) const;

private:
    enum class Encoding : std::uint8_t { Text, BinaryLittleEndian, BinaryBigEndian };
    enum class Scalar : std::uint8_t { Float32, Float64 };

    /// Where a coordinate is stored in mBytes: a text token or binary scalar.
    struct Slot
    {
        std::uint64_t begin = 0;
        std::uint32_t length = 0;
    };

    /// Coordinates of one kind (positions or normals): 3 slots per entry, indexed 3 * entry +
    /// axis; within each entry the slots appear in the file in the order mAxisOrder.
    struct Layout
    {
        std::vector<Slot> slots;
        std::array<int, 3> axisOrder{0, 1, 2};
        std::array<Scalar, 3> types{Scalar::Float64, Scalar::Float64, Scalar::Float64};
    };

    MeshDocument() = default;

    void parseObj();
    void parsePly();
    void parseStl();
    void appendValue(std::string& out, const Layout& layout, std::size_t entry, int axis,
                     double value, double original) const;

    std::string mPath;
    std::string mBytes;
    Format mFormat = Format::Obj;
    Encoding mEncoding = Encoding::Text;
    std::size_t mFaceCount = 0;

    std::vector<openvdb::Vec3d> mPositions, mOriginalPositions;
    std::vector<openvdb::Vec3d> mNormals, mOriginalNormals, mNormalAnchors;
    std::vector<std::uint8_t> mNormalUsed;
    Layout mPositionLayout, mNormalLayout;

    // PLY only.
    std::vector<std::uint64_t> mRowEnds; ///< end of each vertex row (where added values go)
    std::uint64_t mHeaderInsert = 0;     ///< after the vertex element's last property line
    std::string mHeaderNewline = "\n";   ///< line ending of that line
    std::vector<std::string> mVertexPropertyNames;
    std::vector<std::pair<std::string, std::vector<float>>> mAddedProperties;
};

} // namespace vdbmatch
