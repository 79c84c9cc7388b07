/// @file MatrixPlots.h
/// @brief Pictures of a collection's distance matrix (`vdb_match batch collect`): the matrix as
///        a heat map with the shapes in a given order (e.g. eval::clusterOrder), and the shapes
///        placed in the plane by MDS (eval::classicalMds), both labelled with the built-in font.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/eval/DistanceMatrix.h>
#include <vdbmatch/render/Canvas.h>

#include <string>
#include <vector>

namespace vdbmatch {
namespace render {

/// The matrix as coloured cells (Inferno, 0 dark to the largest entry bright), rows and columns
/// in @a order; each row labelled "k name" on the left, columns numbered k on top, a colour bar
/// with its range and @a title. NaN entries are drawn grey.
/// @throw openvdb::ValueError if names or order do not have m.n entries or order is not a
///        permutation
Image8 distanceHeatMap(const eval::DistanceMatrix& m, const std::vector<std::string>& names,
                       const std::vector<int>& order, const std::string& title);

/// The points (e.g. MDS coordinates) as labelled dots in a square frame, equal scales on both
/// axes, and @a title.
/// @throw openvdb::ValueError if names and points differ in size
Image8 labelledScatter(const std::vector<Vec<2>>& points, const std::vector<std::string>& names,
                       const std::string& title);

} // namespace render
} // namespace vdbmatch
