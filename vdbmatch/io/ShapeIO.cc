/// @file ShapeIO.cc
#include "ShapeIO.h"

#include <vdbmatch/geometry/SurfaceExtraction.h>
#include <vdbmatch/io/LevelSetIO.h>
#include <vdbmatch/io/MeshIO.h>
#include <vdbmatch/io/PathText.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace vdbmatch {

namespace {

using detail::lowerExtension;

} // namespace

bool
isLevelSetFile(const std::string& path)
{
    return lowerExtension(path) == ".vdb";
}

bool
isShapeFile(const std::string& path)
{
    const std::string ext = lowerExtension(path);
    return ext == ".vdb" || ext == ".obj" || ext == ".ply" || ext == ".stl" || ext == ".polyline" ||
           ext == ".txt";
}

Shape
readShape(const std::string& path, const std::string& gridName, std::optional<double> isoValue)
{
    Shape in;
    in.path = path;
    if (!std::filesystem::exists(path)) {
        OPENVDB_THROW(openvdb::IoError, "readShape: file '" << path << "' does not exist");
    }
    if (!isShapeFile(path)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "readShape: '" << path
                                     << "': unknown file type (expected .vdb, .obj, .ply, .stl, "
                                        ".polyline or .txt)");
    }
    if (!gridName.empty() && !isLevelSetFile(path)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "readShape: a grid name applies to .vdb files, not to '" << path << "'");
    }
    const std::string ext = lowerExtension(path);
    if (ext == ".vdb") {
        const openvdb::FloatGrid::Ptr grid = isoValue
                                                 ? readLevelSetAtIsoValue(path, gridName, *isoValue)
                                                 : readLevelSet(path, gridName);
        in.grid = grid->getName();
        in.transform = grid->transform().copy();
        const bool converted =
            isoValue && grid->getGridClass() == openvdb::GRID_LEVEL_SET &&
            grid->getMetadata<openvdb::DoubleMetadata>("vdbmatch_iso_value") != nullptr;
        if (isSlice(*grid)) {
            in.format = "level set slice";
            in.dim = 2;
            in.curve = extractCurve(*grid);
        } else {
            in.format = converted ? "density" : "level set";
            if (converted) in.isoValue = *isoValue;
            in.surface = extractSurface(*grid);
        }
    } else if (ext == ".obj" || ext == ".ply" || ext == ".stl") {
        in.format = "mesh";
        in.surface = readMesh(path);
    } else {
        in.format = "polyline";
        in.dim = 2;
        in.curve = readPolyline(path);
    }
    if (in.dim == 3) {
        checkSurface(in.surface, "'" + path + "'");
    } else {
        checkSurface(in.curve, "'" + path + "'");
    }
    return in;
}

} // namespace vdbmatch
