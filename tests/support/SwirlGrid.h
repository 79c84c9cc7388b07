/// @file SwirlGrid.h
/// @brief Test deformation grids: a bijective swirl with large displacements, and an affine map.
#pragma once

#include <openvdb/openvdb.h>

#include <cmath>

namespace vdbmatch {
namespace test {

/// A grid of 2^level + 1 nodes per axis (one layer in 2D) with a swirl about the domain's centre
/// line: the circle of radius r turns by angle(r) = turn * b(r), b a smooth bump vanishing at
/// r = 0.45 of the domain. Each circle is mapped onto itself, so phi is a bijection; a turn of
/// 1.5 rad moves nodes by up to ~10 cells at level 5, far from the fixed-point guess.
inline openvdb::Vec3SGrid::Ptr
swirlGrid(int dim, int level, double turn, double voxelWorld)
{
    const int n = 1 << level;
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    auto acc = grid->getAccessor();
    for (int k = 0; k <= (dim == 3 ? n : 0); ++k) {
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                const double x = double(i) / n - 0.5, y = double(j) / n - 0.5;
                const double z = dim == 3 ? double(k) / n : 0.5;
                const double r = std::sqrt(x * x + y * y);
                const double R = 0.45;
                double bump = r < R ? std::pow(std::cos(0.5 * M_PI * r / R), 2) : 0.0;
                bump *= std::sin(M_PI * z); // vanishes on the z faces
                const double a = turn * bump;
                const double rx = std::cos(a) * x - std::sin(a) * y;
                const double ry = std::sin(a) * x + std::cos(a) * y;
                acc.setValueOn(openvdb::Coord(i, j, k),
                               openvdb::Vec3s(float((rx - x) * n * voxelWorld),
                                              float((ry - y) * n * voxelWorld), 0.0f));
            }
        }
    }
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelWorld));
    grid->transform().postTranslate(openvdb::Vec3d(-3.0, 1.0, 2.0));
    return grid;
}

/// A grid of 2^level + 1 nodes per axis (one layer in 2D), voxel @a voxelWorld, origin at the
/// world origin, holding the affine map phi(x) = c + A (x - c) + b about the domain centre c.
/// (Inside the node box phi is exactly affine; beyond it the grid's u falls to 0.)
inline openvdb::Vec3SGrid::Ptr
affineGrid(int dim, int level, const openvdb::Mat3d& A, const openvdb::Vec3d& b, double voxelWorld)
{
    const int n = 1 << level;
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxelWorld));
    const openvdb::Vec3d c(0.5 * n * voxelWorld, 0.5 * n * voxelWorld,
                           dim == 3 ? 0.5 * n * voxelWorld : 0.0);
    auto acc = grid->getAccessor();
    for (int k = 0; k <= (dim == 3 ? n : 0); ++k) {
        for (int j = 0; j <= n; ++j) {
            for (int i = 0; i <= n; ++i) {
                const openvdb::Vec3d x = grid->indexToWorld(openvdb::Coord(i, j, k));
                const openvdb::Vec3d u = A * (x - c) + b - (x - c);
                acc.setValueOn(openvdb::Coord(i, j, k), openvdb::Vec3s(u));
            }
        }
    }
    return grid;
}

} // namespace test
} // namespace vdbmatch
