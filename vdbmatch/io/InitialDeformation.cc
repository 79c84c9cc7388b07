/// @file InitialDeformation.cc
#include "InitialDeformation.h"

#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/DeformationIO.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace vdbmatch {

namespace {

/// Relative tolerance of the placement check, in node spacings (the grid stores its transform
/// in double precision; placements of the same inputs agree to rounding).
constexpr double PLACEMENT_TOLERANCE = 1e-5;

/// Largest grid level accepted (makeDeformationGrid writes at most 12).
constexpr int MAX_GRID_LEVEL = 12;

/// sqrt(sum_a max over the edges e along axis a of |e_a + du/H|^2): an upper bound of the
/// spectral norm of D phi on every Kuhn simplex of the grid (its columns are such differences,
/// and |A|_2 <= |A|_F), at least 1.
double
gridLipschitzBound(const openvdb::Vec3SGrid& grid, int dim)
{
    double maxColumn[3] = {1, 1, 1};
    const double H = grid.voxelSize()[0];
    auto acc = grid.getConstAccessor();
    for (auto v = grid.cbeginValueOn(); v; ++v) {
        const openvdb::Coord ijk = v.getCoord();
        const openvdb::Vec3d u0 = *v;
        for (int a = 0; a < dim; ++a) {
            openvdb::Coord next = ijk;
            next[a] += 1;
            openvdb::Vec3d column = (openvdb::Vec3d(acc.getValue(next)) - u0) / H;
            column[a] += 1;
            maxColumn[a] = std::max(maxColumn[a], column.lengthSqr());
        }
    }
    double sum = 0;
    for (int a = 0; a < dim; ++a)
        sum += maxColumn[a];
    return std::max(1.0, std::sqrt(sum));
}

/// "4..7" -> {4, 7}; false if the text is not of that form.
bool
parseLevels(const std::string& text, int& first, int& last)
{
    const std::size_t dots = text.find("..");
    if (dots == std::string::npos) return false;
    try {
        std::size_t end = 0;
        first = std::stoi(text.substr(0, dots), &end);
        if (end != dots) return false;
        const std::string tail = text.substr(dots + 2);
        last = std::stoi(tail, &end);
        return end == tail.size() && first <= last;
    } catch (const std::exception&) {
        return false;
    }
}

} // namespace

InitialDeformation
initialDeformationFromGrid(openvdb::Vec3SGrid::ConstPtr grid, const UnitBoxPlacement& placement,
                           int dim, const std::string& what, InitPlacement mode)
{
    auto field = std::make_shared<const DeformationField>(grid); // checks the transform
    if (field->dimension() != dim) {
        OPENVDB_THROW(openvdb::ValueError, what << " is a " << field->dimension()
                                                << "D deformation but the inputs are " << dim
                                                << "D");
    }
    // The nodes of Omega at level L: indices [0, 2^L] on every axis (k = const in 2D).
    openvdb::CoordBBox box;
    grid->tree().evalActiveVoxelBoundingBox(box);
    const int n = box.max()[0];
    int level = 0;
    while (level <= MAX_GRID_LEVEL && (1 << level) < n)
        ++level;
    bool nodesOfOmega = n >= 2 && (1 << level) == n && level <= MAX_GRID_LEVEL;
    for (int a = 0; a < dim; ++a)
        nodesOfOmega = nodesOfOmega && box.min()[a] == 0 && box.max()[a] == n;
    if (!nodesOfOmega) {
        OPENVDB_THROW(openvdb::ValueError,
                      what << " is not a deformation grid of vdb_match match: its active voxels "
                              "do not cover the nodes [0, 2^L]^d of the unit box (index box "
                           << box << ")");
    }
    // The placement: voxel size 2^-L / s and index origin at worldOrigin (2D: its x, y).
    const double H = std::ldexp(1.0, -level);
    const double gridScale = H / grid->voxelSize()[0];
    const openvdb::Vec3d gridOrigin = grid->transform().indexToWorld(openvdb::Vec3d(0.0));
    const double worldTolerance = PLACEMENT_TOLERANCE * H / placement.scale;
    bool same = std::abs(gridScale - placement.scale) <= PLACEMENT_TOLERANCE * placement.scale;
    for (int a = 0; a < dim; ++a)
        same = same && std::abs(gridOrigin[a] - placement.worldOrigin[a]) <= worldTolerance;
    if (!same && mode == InitPlacement::Same) {
        std::ostringstream s;
        s << what << " was computed for another placement of the shapes in the unit box (scale "
          << gridScale << ", origin " << gridOrigin << "; these inputs: scale " << placement.scale
          << ", origin " << placement.worldOrigin << ")";
        const auto margin = grid->getMetadata<openvdb::DoubleMetadata>("vdbmatch_margin");
        if (margin && margin->value() != placement.margin) {
            s << ": it used --margin " << margin->value() << ", this run --margin "
              << placement.margin;
        } else {
            s << ": give --init a result of the same SOURCE and TARGET";
        }
        OPENVDB_THROW(openvdb::ValueError, s.str());
    }

    InitialDeformation init;
    init.gridLevel = level;
    init.firstLevel = level;
    init.finestLevel = level;
    if (auto levels = grid->getMetadata<openvdb::StringMetadata>("vdbmatch_levels")) {
        int first = 0, last = 0;
        if (parseLevels(levels->value(), first, last) && last >= level && last <= MAX_GRID_LEVEL) {
            init.firstLevel = first;
            init.finestLevel = last;
        }
    }
    if (auto flag = grid->getMetadata<openvdb::BoolMetadata>("is_interrupted")) {
        init.interrupted = flag->value();
    }

    auto start = std::make_shared<InitialDisplacement>();
    start->lipschitz = gridLipschitzBound(*grid, dim);
    start->description = what;
    const UnitBoxPlacement p = placement;
    // Same placement: the grid's nodes are Omega's. Carried: phi(x') - x' at the world point x'
    // of x, in the current Omega units (0 where x' is outside the earlier Omega).
    start->displacement = [field, p](const openvdb::Vec3d& xUnit) {
        return field->displacement(p.toWorld(xUnit)) * p.scale;
    };
    init.start = start;
    return init;
}

InitialDeformation
readInitialDeformation(const std::string& path, const UnitBoxPlacement& placement, int dim,
                       InitPlacement mode)
{
    return initialDeformationFromGrid(
        readDeformation(path), placement, dim,
        (mode == InitPlacement::Same ? "--init '" : "--warm-start '") + path + "'", mode);
}

} // namespace vdbmatch
