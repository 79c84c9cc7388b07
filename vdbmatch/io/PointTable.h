/// @file PointTable.h
/// @brief A table of points (.csv, .xyz, .txt) kept whole, so that its coordinates can be
///        overwritten and the file written back with every other field unchanged (as
///        antsApplyTransformsToPoints does for its CSV files).
///
/// Formats, each with one header line naming the columns:
/// - `.csv`: comma-separated; fields may be double-quoted (`"a,b"`, `""` for a quote inside);
///   a quoted field does not span lines. Lines starting with `#` before the header are comments.
/// - `.xyz`, `.txt`: separated by spaces or tabs; the header line may start with `#`
///   (`# x y z label`).
///
/// The columns `x`, `y` and (in 3D) `z` are found by name, case-insensitively and ignoring
/// surrounding spaces; every other column (`t`, `label`, `id`, strings) is carried as text. After
/// the header, lines starting with `#` and blank lines are kept verbatim and hold no point. Line
/// endings (LF or CRLF) and a UTF-8 byte-order mark are kept. Coordinates are in the units of the
/// file (world units).
#pragma once

#include <openvdb/Types.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace vdbmatch {

/// A point file read whole, with editable coordinates.
class PointTable
{
public:
    /// Reads a point table.
    /// @param path       a .csv, .xyz or .txt file (extension case-insensitive)
    /// @param dimension  2 or 3: the coordinate columns required and rewritten (2: x and y; a z
    ///                   column is then optional, read into positions() but written as-is)
    /// @throw openvdb::IoError if the file is missing, a directory or unreadable
    /// @throw openvdb::ValueError naming the file (and line) if the dimension or extension is
    ///        invalid, the header is missing, a coordinate column is missing ("column 'z'
    ///        missing") or repeated, a row has the wrong number of fields, a quote is not
    ///        closed, or a coordinate is not a finite number
    static PointTable read(const std::string& path, int dimension);

    int dimension() const { return mDimension; }
    /// Number of points (data rows).
    std::size_t size() const { return mPositions.size(); }
    /// Column names as in the header (trimmed, without enclosing quotes).
    const std::vector<std::string>& columns() const { return mColumns; }

    /// One position per data row, in file order; in 2D, z is the file's z or 0. Overwrite the
    /// values; do not resize the vector (write() checks).
    std::vector<openvdb::Vec3d>& positions() { return mPositions; }
    const std::vector<openvdb::Vec3d>& positions() const { return mPositions; }

    /// The file as write() would store it.
    /// @throw openvdb::ValueError if positions() was resized or a changed coordinate is not
    ///        finite
    std::string render() const;

    /// Writes the table with the same separator, header, comments and other fields verbatim;
    /// unchanged coordinates keep their text, changed ones are written with round-trip precision
    /// (shortest text reading back the same double). Atomic: no partial file is left at @a path.
    /// @throw openvdb::ValueError as render()
    /// @throw openvdb::IoError naming @a path if it cannot be written
    void write(const std::string& path) const;

private:
    /// Where a coordinate is stored in mBytes.
    struct Slot
    {
        std::uint64_t begin = 0;
        std::uint32_t length = 0;
    };

    PointTable() = default;
    void parse(bool commaSeparated);

    std::string mPath;
    std::string mBytes;
    int mDimension = 3;
    std::vector<std::string> mColumns;
    std::vector<openvdb::Vec3d> mPositions, mOriginalPositions;
    /// mDimension slots per point, indexed mDimension * point + axis.
    std::vector<Slot> mSlots;
    /// Axes in the order their columns appear in a row.
    std::array<int, 3> mAxisOrder{0, 1, 2};
};

} // namespace vdbmatch
