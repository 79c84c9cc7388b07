/// @file ShapeIO.h
/// @brief Reading one input shape of a matching problem from any supported file: a level set
///        (.vdb; a one-voxel-thick slice is a 2D shape), a mesh (.obj, .ply, .stl) or a closed
///        2D polyline (.polyline, .txt), as a Surface<3> or Surface<2> in world space.
///
/// Level sets are read and checked with readLevelSet (LevelSetIO.h) and their zero level set is
/// extracted (extractSurface: triangles; extractCurve for slices: segments); meshes and
/// polylines are read with MeshIO.h. Every shape is checked with checkSurface (closed, finite,
/// not empty or degenerate).
#pragma once

#include <vdbmatch/geometry/Surface.h>

#include <openvdb/openvdb.h>

#include <optional>
#include <string>

namespace vdbmatch {

/// An input shape as read.
struct Shape
{
    std::string path;
    std::string format; ///< "level set", "level set slice", "density", "mesh" or "polyline"
    std::string grid;   ///< name of the grid read (level sets only)
    int dim = 3;        ///< 3: surface holds the shape; 2: curve holds it
    Surface<3> surface; ///< world space
    Surface<2> curve;   ///< world space, plane z = 0 (slices: the slice's x, y)
    /// The iso value a density (format "density") was converted at, else unset.
    std::optional<double> isoValue;
    /// Index-to-world transform of a level set input, else null.
    openvdb::math::Transform::Ptr transform;

    template <int D> const Surface<D>& get() const
    {
        if constexpr (D == 3) {
            return surface;
        } else {
            return curve;
        }
    }
};

/// True if @a path has an extension readShape understands (case-insensitive).
bool isShapeFile(const std::string& path);
/// True for level set files (.vdb), the only ones where a grid name applies.
bool isLevelSetFile(const std::string& path);

/// Reads a shape; the file type comes from the extension (case-insensitive).
/// @param gridName  grid to read from a .vdb file (empty: its only float grid); must be empty
///                  for other files
/// @throw openvdb::IoError if the file is missing or unreadable
/// @throw openvdb::ValueError for an unknown extension, a grid name given for a non-.vdb file,
///        or invalid content (as readLevelSet, readMesh, readPolyline, checkSurface)
/// @param isoValue  if set, a .vdb grid that is not a level set (a fog volume, a density) is
///                  converted to the level set of its iso-surface at this value
///                  (readLevelSetAtIsoValue; format "density"); level sets are read as usual
Shape readShape(const std::string& path, const std::string& gridName = "",
                std::optional<double> isoValue = std::nullopt);

} // namespace vdbmatch
