/// @file LevelSetIO.cc
/// @brief Reading and checking input level sets, atomic .vdb writes.
#include "LevelSetIO.h"

#include "AtomicFile.h"
#include "VdbFileCheck.h"

#include <openvdb/io/File.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <limits>
#include <sstream>
#include <system_error>
#include <vector>

namespace vdbmatch {

namespace {

/// The outermost active voxels of a closed level set lie at least this many voxels outside the
/// surface. A narrow band of any useful width (>= 1 voxel on each side) satisfies it.
constexpr double MIN_OUTER_LAYER_DISTANCE_VOXELS = 0.5;

std::string
quoted(const std::string& s)
{
    return "'" + s + "'";
}

/// "'a' (float), 'b' (vec3s)" for the grids of a file.
std::string
describeGrids(const openvdb::GridPtrVec& grids)
{
    std::string out;
    for (const auto& g : grids) {
        if (!out.empty()) out += ", ";
        out += (g->getName().empty() ? std::string("(unnamed)") : quoted(g->getName())) + " (" +
               g->valueType() + ")";
    }
    return out.empty() ? std::string("none") : out;
}

std::string
coordString(const openvdb::Coord& c)
{
    std::ostringstream s;
    s << "(" << c[0] << ", " << c[1] << ", " << c[2] << ")";
    return s.str();
}

} // namespace

void
checkInputLevelSet(const openvdb::FloatGrid& grid, const std::string& context)
{
    if (grid.getGridClass() != openvdb::GRID_LEVEL_SET) {
        OPENVDB_THROW(openvdb::ValueError,
                      context + " is not a level set (grid class " +
                          quoted(openvdb::GridBase::gridClassToString(grid.getGridClass())) +
                          "); expected a signed distance of class 'level set'");
    }
    const openvdb::math::Transform& xform = grid.transform();
    if (!xform.isLinear()) {
        OPENVDB_THROW(openvdb::ValueError, context + " has a non-linear (" + xform.mapType() +
                                               ") transform; expected a linear transform");
    }
    if (!grid.hasUniformVoxels()) {
        std::ostringstream s;
        s << context << " has non-uniform voxels (voxel size " << grid.voxelSize()
          << ", or a sheared transform); expected cubic voxels";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    const double h = grid.voxelSize()[0];
    const float background = grid.background();
    if (!std::isfinite(background) || !(background > 0.0f)) {
        std::ostringstream s;
        s << context << " has the background value " << background
          << "; expected a positive, finite outside distance";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    if (grid.tree().hasActiveTiles()) {
        OPENVDB_THROW(openvdb::ValueError,
                      context + " has active tiles; expected a narrow-band level set (active "
                                "voxels only)");
    }

    openvdb::CoordBBox activeBox;
    if (!grid.tree().evalActiveVoxelBoundingBox(activeBox)) {
        OPENVDB_THROW(openvdb::ValueError, context + " is empty (no active voxels)");
    }

    // One pass over the leaves: finite values, signs of the active values, outer layer.
    float minActive = std::numeric_limits<float>::max();
    float maxActive = -std::numeric_limits<float>::max();
    const float minOuter = float(MIN_OUTER_LAYER_DISTANCE_VOXELS * h);
    // A 2D shape is a slice: one layer of voxels in z, whose z faces are the slice itself.
    const int faceAxes = activeBox.min()[2] == activeBox.max()[2] ? 2 : 3;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        for (auto it = leaf->cbeginValueAll(); it; ++it) {
            const float d = *it;
            if (!std::isfinite(d)) {
                OPENVDB_THROW(openvdb::ValueError, context +
                                                       " has a non-finite value (NaN or inf) "
                                                       "at voxel " +
                                                       coordString(it.getCoord()));
            }
            if (!it.isValueOn()) continue;
            minActive = std::min(minActive, d);
            maxActive = std::max(maxActive, d);
            const openvdb::Coord ijk = it.getCoord();
            bool onFace = false;
            for (int a = 0; a < faceAxes; ++a) {
                onFace = onFace || ijk[a] == activeBox.min()[a] || ijk[a] == activeBox.max()[a];
            }
            if (onFace && d < minOuter) {
                std::ostringstream s;
                s << context << " has the value " << d << " at voxel " << coordString(ijk)
                  << " on the edge of its narrow band (active bounding box " << activeBox
                  << "): the surface is open or clipped, or the sign is flipped; expected a "
                     "closed surface, negative inside";
                OPENVDB_THROW(openvdb::ValueError, s.str());
            }
        }
    }
    for (auto tile = grid.tree().cbeginValueAll(); tile; ++tile) {
        if (tile.isVoxelValue()) continue;
        if (!std::isfinite(*tile)) {
            OPENVDB_THROW(openvdb::ValueError,
                          context + " has a non-finite tile value (NaN or inf)");
        }
    }
    if (minActive > 0.0f || maxActive < 0.0f) {
        std::ostringstream s;
        s << context << " has no zero crossing (active values in [" << minActive << ", "
          << maxActive << "]); expected a surface";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
}

openvdb::FloatGrid::Ptr
readLevelSet(const std::string& path, const std::string& gridName)
{
    openvdb::initialize();
    const std::string where = "readLevelSet: file " + quoted(path);

    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(status)) {
        OPENVDB_THROW(openvdb::IoError, where + " does not exist");
    }
    if (std::filesystem::is_directory(status)) {
        OPENVDB_THROW(openvdb::IoError, where + " is a directory");
    }
    // OpenVDB allocates from the lengths in the file before reading the bytes (a truncated
    // file made it allocate gigabytes): check them against the file size first.
    checkVdbFileStructure(path, where);

    openvdb::io::File file(path);
    openvdb::GridPtrVecPtr metadata;
    try {
        file.open(/*delayLoad=*/false);
        metadata = file.readAllGridMetadata();
    } catch (const std::exception& e) {
        OPENVDB_THROW(openvdb::IoError,
                      where + " cannot be read as a VDB file (" + std::string(e.what()) + ")");
    }

    // Select the grid among the grid descriptors (metadata only).
    std::vector<size_t> floatGrids, named;
    for (size_t i = 0; i < metadata->size(); ++i) {
        const openvdb::GridBase& g = *(*metadata)[i];
        if (g.isType<openvdb::FloatGrid>()) floatGrids.push_back(i);
        if (!gridName.empty() && g.getName() == gridName) named.push_back(i);
    }
    size_t index = 0;
    if (!gridName.empty()) {
        if (named.empty()) {
            OPENVDB_THROW(openvdb::ValueError, where + " has no grid named " + quoted(gridName) +
                                                   " (grids: " + describeGrids(*metadata) + ")");
        }
        if (named.size() > 1) {
            OPENVDB_THROW(openvdb::ValueError,
                          where + " has several grids named " + quoted(gridName));
        }
        index = named.front();
        if (!(*metadata)[index]->isType<openvdb::FloatGrid>()) {
            OPENVDB_THROW(openvdb::TypeError, where + ": grid " + quoted(gridName) + " holds " +
                                                  (*metadata)[index]->valueType() +
                                                  " values; expected a float level set");
        }
    } else {
        if (floatGrids.empty()) {
            OPENVDB_THROW(openvdb::TypeError,
                          where + " has no float grid (grids: " + describeGrids(*metadata) +
                              "); expected a float level set");
        }
        if (floatGrids.size() > 1) {
            openvdb::GridPtrVec candidates;
            for (size_t i : floatGrids)
                candidates.push_back((*metadata)[i]);
            OPENVDB_THROW(openvdb::ValueError, where + " has several float grids (" +
                                                   describeGrids(candidates) +
                                                   "); name the one to use");
        }
        index = floatGrids.front();
    }

    // Read it: by name when that is unambiguous, else all grids (unnamed or repeated names).
    const std::string name = (*metadata)[index]->getName();
    size_t sameName = 0;
    for (const auto& g : *metadata)
        sameName += g->getName() == name ? 1 : 0;
    openvdb::GridBase::Ptr base;
    try {
        if (!name.empty() && sameName == 1) {
            base = file.readGrid(name);
        } else {
            openvdb::GridPtrVecPtr all = file.getGrids();
            if (all && all->size() == metadata->size()) base = (*all)[index];
        }
        file.close();
    } catch (const std::exception& e) {
        OPENVDB_THROW(openvdb::IoError,
                      where + " is corrupt or unreadable (" + std::string(e.what()) + ")");
    }
    openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    if (!grid) OPENVDB_THROW(openvdb::IoError, where + ": the selected grid could not be read");

    checkInputLevelSet(*grid, where + ", grid " +
                                  (name.empty() ? std::string("(unnamed)") : quoted(name)));
    return grid;
}

void
writeGridsAtomically(const std::string& path, const openvdb::GridPtrVec& grids,
                     const openvdb::MetaMap& fileMeta)
{
    // openvdb::io::File writes by file name (it records grid offsets for delayed loading), so
    // the temporary file is written through its name.
    writeFileAtomicallyVia(
        path,
        [&](const std::string& tempPath) {
            openvdb::io::File file(tempPath);
            file.write(grids, fileMeta);
            file.close();
        },
        "writeGridsAtomically");
}

} // namespace vdbmatch
