/// @file LevelSetIO.cc
/// @brief Reading and checking input level sets, atomic .vdb writes.
#include "LevelSetIO.h"

#include "AtomicFile.h"
#include "VdbFileCheck.h"

#include <vdbmatch/io/InputFile.h>
#include <vdbmatch/io/PathText.h>

#include <openvdb/io/File.h>
#include <openvdb/tools/LevelSetRebuild.h>

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

using detail::quoted;

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

/// A fog volume, or a float grid whose values (active, inactive, background) all lie in [0, 1]:
/// a density rather than a signed distance.
bool
looksLikeDensity(const openvdb::FloatGrid& grid)
{
    if (grid.getGridClass() == openvdb::GRID_FOG_VOLUME) return true;
    const float background = grid.background();
    if (!(background >= 0.0f && background <= 1.0f)) return false;
    for (auto it = grid.cbeginValueAll(); it; ++it) {
        const float v = *it;
        if (!(v >= 0.0f && v <= 1.0f)) return false;
    }
    return true;
}

/// What to do with a density given where a level set is expected.
std::string
densityHint(const openvdb::FloatGrid& grid)
{
    if (!looksLikeDensity(grid)) return "";
    return ": it is a density (fog volume, values in [0, 1]), not a signed distance; convert it "
           "to the level set of its iso-surface with --iso-value X (the density at the surface, "
           "e.g. 0.5; readLevelSetAtIsoValue)";
}

} // namespace

void
checkInputLevelSet(const openvdb::FloatGrid& grid, const std::string& context)
{
    if (grid.getGridClass() != openvdb::GRID_LEVEL_SET) {
        const std::string hint = densityHint(grid);
        OPENVDB_THROW(
            openvdb::ValueError,
            context + " is not a level set (grid class " +
                quoted(openvdb::GridBase::gridClassToString(grid.getGridClass())) + ")" +
                (hint.empty() ? "; expected a signed distance of class 'level set'" : hint));
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
    if (!(h > MIN_WORLD_VOXEL_SIZE)) {
        std::ostringstream s;
        s << context << " has the voxel size " << h << ", at or below " << MIN_WORLD_VOXEL_SIZE
          << ", the smallest voxel OpenVDB's transforms represent (their determinant h^3 must "
             "exceed 1e-15); rescale the input (e.g. to millimetres)";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    if (!(h <= MAX_WORLD_VOXEL_SIZE)) {
        std::ostringstream s;
        s << context << " has the voxel size " << h << ", above " << MAX_WORLD_VOXEL_SIZE
          << ": world coordinates and distances would overflow single precision; rescale the "
             "input";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    const float background = grid.background();
    if (!std::isfinite(background) || !(background > 0.0f)) {
        std::ostringstream s;
        s << context << " has the background value " << background
          << "; expected a positive, finite outside distance" << densityHint(grid);
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

namespace {

/// Reads the float grid of a file selected as readLevelSet() does, unchecked; @a context gets
/// the grid's description for messages.
openvdb::FloatGrid::Ptr
readFloatGrid(const std::string& path, const std::string& gridName, const std::string& where,
              std::string& context)
{
    openvdb::initialize();

    checkInputFile(path, where);
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

    context = where + ", grid " + (name.empty() ? std::string("(unnamed)") : quoted(name));
    return grid;
}

} // namespace

openvdb::FloatGrid::Ptr
readLevelSet(const std::string& path, const std::string& gridName)
{
    std::string context;
    openvdb::FloatGrid::Ptr grid =
        readFloatGrid(path, gridName, "readLevelSet: file " + quoted(path), context);
    checkInputLevelSet(*grid, context);
    return grid;
}

openvdb::FloatGrid::Ptr
levelSetAtIsoValue(const openvdb::FloatGrid& density, double isoValue, const std::string& context)
{
    if (density.getGridClass() == openvdb::GRID_LEVEL_SET) {
        checkInputLevelSet(density, context);
        return density.deepCopy();
    }
    if (!std::isfinite(isoValue)) {
        OPENVDB_THROW(openvdb::ValueError, "the iso value must be finite");
    }
    if (!density.transform().isLinear() || !density.hasUniformVoxels()) {
        OPENVDB_THROW(openvdb::ValueError,
                      context + " needs a linear transform with cubic voxels to be converted");
    }
    openvdb::CoordBBox box;
    if (!density.tree().evalActiveVoxelBoundingBox(box)) {
        OPENVDB_THROW(openvdb::ValueError, context + " is empty (no active voxels)");
    }
    if (box.min()[2] == box.max()[2]) {
        OPENVDB_THROW(openvdb::ValueError,
                      context + " is one voxel thick: a 2D density cannot be converted by "
                                "--iso-value; give a 2D level set slice or a polyline");
    }
    // Inside is where the density exceeds the iso value: negate it so that inside is below.
    openvdb::FloatGrid::Ptr negated = density.deepCopy();
    float lo = std::numeric_limits<float>::max(), hi = -lo;
    for (auto it = negated->beginValueAll(); it; ++it) {
        const float v = *it;
        if (!std::isfinite(v)) {
            OPENVDB_THROW(openvdb::ValueError,
                          context + " has a non-finite value (NaN or inf) at voxel " +
                              coordString(it.getCoord()));
        }
        if (it.isValueOn()) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
        it.setValue(-v);
    }
    if (!(lo < isoValue && hi > isoValue)) {
        std::ostringstream s;
        s << context << " has no iso-surface at " << isoValue << " (active values in [" << lo
          << ", " << hi << "]); choose an iso value between them";
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }
    negated->tree().root().setBackground(-density.background(), /*updateChildNodes=*/false);
    openvdb::FloatGrid::Ptr levelSet = openvdb::tools::levelSetRebuild(
        *negated, float(-isoValue), float(ISO_LEVEL_SET_HALF_WIDTH));
    levelSet->setName(density.getName());
    levelSet->setGridClass(openvdb::GRID_LEVEL_SET);
    levelSet->insertMeta("vdbmatch_iso_value", openvdb::DoubleMetadata(isoValue));
    checkInputLevelSet(
        *levelSet, context + " at iso value " + [&] {
            std::ostringstream s;
            s << isoValue;
            return s.str();
        }());
    return levelSet;
}

openvdb::FloatGrid::Ptr
readLevelSetAtIsoValue(const std::string& path, const std::string& gridName, double isoValue)
{
    std::string context;
    const openvdb::FloatGrid::Ptr grid =
        readFloatGrid(path, gridName, "readLevelSetAtIsoValue: file " + quoted(path), context);
    return levelSetAtIsoValue(*grid, isoValue, context);
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
