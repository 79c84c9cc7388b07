/// @file DenseLattice.h
/// @brief The nodes of the dense lattice of [0,1]^D at one level, x fastest, and the signed
///        distance of a closed surface on them from a narrow band (negative inside; off the band
///        +-background): the lattice the interior walks of Extremities.cc (Dijkstra) and
///        InnerDistance.cc (fast marching) run on.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/Surface.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace vdbmatch {
namespace detail {

/// Linear indices of the (n+1)^D nodes of the lattice with n = 2^level cells per axis.
template <int D> struct DenseIndex
{
    int n = 0;
    std::array<int64_t, D> stride{};
    int64_t size = 1;

    explicit DenseIndex(int cells) : n(cells)
    {
        for (int a = 0; a < D; ++a) {
            stride[a] = size;
            size *= n + 1;
        }
    }
    std::array<int, D> coords(int64_t i) const { return coords(i, n); }
    /// The lattice coordinates of node @a i of the lattice with @a cells cells per axis.
    static std::array<int, D> coords(int64_t i, int cells)
    {
        std::array<int, D> c;
        for (int a = 0; a < D; ++a) {
            c[a] = int(i % (cells + 1));
            i /= cells + 1;
        }
        return c;
    }
};

/// The signed distance of @a surface (Omega units) on every node of the lattice of @a level,
/// from distanceBand() (MIN_DISTANCE_HALF_WIDTH_VOXELS): the distance within the band, the
/// band's +-background beyond it, so the sign says inside everywhere. @a background receives
/// the band's background.
template <int D>
std::vector<float>
denseBandDistance(const Surface<D>& surface, int level, bool threaded, float& background)
{
    const openvdb::FloatGrid::Ptr grid =
        distanceBand<D>(surface, level, MIN_DISTANCE_HALF_WIDTH_VOXELS, threaded);
    background = grid->background();
    const auto acc = grid->getConstAccessor();
    const DenseIndex<D> index(1 << level);
    std::vector<float> distance(std::size_t(index.size));
    for (int64_t i = 0; i < index.size; ++i) {
        const std::array<int, D> c = index.coords(i);
        distance[std::size_t(i)] = acc.getValue(openvdb::Coord(c[0], c[1], D == 3 ? c[D - 1] : 0));
    }
    return distance;
}

} // namespace detail
} // namespace vdbmatch
