/// @file DeformationField.cc
#include "DeformationField.h"

#include <vdbmatch/io/DeformationIO.h>

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace vdbmatch {

namespace {

using ConstAccessor = openvdb::tree::ValueAccessor<const openvdb::Vec3STree, /*IsSafe=*/false>;

} // namespace

DeformationField::DeformationField(openvdb::Vec3SGrid::ConstPtr grid) : mGrid(std::move(grid))
{
    if (!mGrid) OPENVDB_THROW(openvdb::ValueError, "DeformationField: null grid");
    const openvdb::math::Transform& xform = mGrid->transform();
    if (!xform.isLinear() || !mGrid->hasUniformVoxels()) {
        OPENVDB_THROW(openvdb::ValueError,
                      "DeformationField: the grid needs a linear transform with uniform voxels");
    }
    // A scale and a translation only: the Kuhn split is defined along the index axes.
    const openvdb::Mat4d m = xform.baseMap()->getAffineMap()->getMat4();
    const double s = mGrid->voxelSize()[0];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
            if (std::abs(m(i, j) - (i == j ? s : 0.0)) > 1e-9 * s) {
                OPENVDB_THROW(openvdb::ValueError,
                              "DeformationField: the grid's transform must be a uniform scale "
                              "and a translation (no rotation)");
            }
        }
    }
    mVoxelSize = s;
    openvdb::CoordBBox box;
    if (!mGrid->tree().evalActiveVoxelBoundingBox(box)) {
        OPENVDB_THROW(openvdb::ValueError, "DeformationField: the grid has no active voxel");
    }
    mDim = box.min()[2] == box.max()[2] ? 2 : 3;
    mSliceK = box.min()[2];
    mWorldBounds = openvdb::BBoxd(xform.indexToWorld(box.min()), xform.indexToWorld(box.max()));
}

DeformationField
DeformationField::read(const std::string& path)
{
    return DeformationField(readDeformation(path));
}

void
DeformationField::locate(const openvdb::Vec3d& xWorld, openvdb::Coord* vertices, double* weights,
                         int* axes) const
{
    const openvdb::Vec3d p = mGrid->transform().worldToIndex(xWorld);
    openvdb::Coord origin;
    std::array<double, 3> t{{0, 0, 0}};
    for (int a = 0; a < 3; ++a) {
        const double f = std::floor(p[a]);
        origin[a] = int(f);
        t[a] = p[a] - f;
    }
    if (mDim == 2) {
        origin[2] = mSliceK;
        t[2] = 0;
    }
    // Axes by decreasing t (ties: lower axis first, any choice gives the same value).
    std::array<int, 3> order{{0, 1, 2}};
    std::stable_sort(order.begin(), order.begin() + mDim,
                     [&](int a, int b) { return t[a] > t[b]; });
    vertices[0] = origin;
    weights[0] = 1.0 - t[order[0]];
    for (int m = 1; m <= mDim; ++m) {
        vertices[m] = vertices[m - 1];
        vertices[m][order[m - 1]] += 1;
        axes[m - 1] = order[m - 1];
        weights[m] = m < mDim ? t[order[m - 1]] - t[order[m]] : t[order[mDim - 1]];
    }
}

openvdb::Vec3d
DeformationField::displacement(const openvdb::Vec3d& xWorld) const
{
    openvdb::Coord v[4];
    double w[4];
    int axes[3];
    locate(xWorld, v, w, axes);
    ConstAccessor acc(mGrid->tree());
    openvdb::Vec3d u(0.0);
    for (int m = 0; m <= mDim; ++m) {
        if (w[m] == 0.0) continue;
        u += openvdb::Vec3d(acc.getValue(v[m])) * w[m];
    }
    return u;
}

double
DeformationField::jacobianDeterminant(const openvdb::Vec3d& xWorld) const
{
    openvdb::Coord v[4];
    double w[4];
    int axes[3];
    locate(xWorld, v, w, axes);
    ConstAccessor acc(mGrid->tree());
    // Column axes[m-1] of D u: the difference along the path step, per voxel size.
    openvdb::Mat3d A = openvdb::Mat3d::identity();
    for (int m = 1; m <= mDim; ++m) {
        const openvdb::Vec3d du =
            (openvdb::Vec3d(acc.getValue(v[m])) - openvdb::Vec3d(acc.getValue(v[m - 1]))) /
            mVoxelSize;
        for (int r = 0; r < mDim; ++r)
            A(r, axes[m - 1]) += du[r];
    }
    if (mDim == 2) return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
    return A.det();
}

} // namespace vdbmatch
