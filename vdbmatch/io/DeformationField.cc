/// @file DeformationField.cc
#include "DeformationField.h"

#include <vdbmatch/io/DeformationIO.h>

#include <openvdb/Exceptions.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>

namespace vdbmatch {

using ConstAccessor = DeformationField::Accessor;

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
    locateIndex(mGrid->transform().worldToIndex(xWorld), vertices, weights, axes);
}

namespace {

/// DeformationField::locateIndex for a field of dimension @a dim (slice @a sliceK in 2D). A
/// function of its own so that the inverse walk inlines it (a member of the shared library is
/// not inlined into another member: it could be interposed).
inline void
kuhnLocate(int dim, int sliceK, const openvdb::Vec3d& p, openvdb::Coord* vertices, double* weights,
           int* axes)
{
    openvdb::Coord origin;
    std::array<double, 3> t{{0, 0, 0}};
    for (int a = 0; a < 3; ++a) {
        const double f = std::floor(p[a]);
        origin[a] = int(f);
        t[a] = p[a] - f;
    }
    if (dim == 2) {
        origin[2] = sliceK;
        t[2] = 0;
    }
    // Axes by decreasing t (ties: lower axis first, any choice gives the same value).
    // (Insertion sort: stable, and unlike std::stable_sort it never allocates a buffer.)
    std::array<int, 3> order{{0, 1, 2}};
    for (int i = 1; i < dim; ++i)
        for (int j = i; j > 0 && t[order[j]] > t[order[j - 1]]; --j)
            std::swap(order[j], order[j - 1]);
    vertices[0] = origin;
    weights[0] = 1.0 - t[order[0]];
    for (int m = 1; m <= dim; ++m) {
        vertices[m] = vertices[m - 1];
        vertices[m][order[m - 1]] += 1;
        axes[m - 1] = order[m - 1];
        weights[m] = m < dim ? t[order[m - 1]] - t[order[m]] : t[order[dim - 1]];
    }
}

} // namespace

void
DeformationField::locateIndex(const openvdb::Vec3d& p, openvdb::Coord* vertices, double* weights,
                              int* axes) const
{
    kuhnLocate(mDim, mSliceK, p, vertices, weights, axes);
}

openvdb::Vec3d
DeformationField::displacement(const openvdb::Vec3d& xWorld) const
{
    ConstAccessor acc(mGrid->tree());
    return displacement(xWorld, acc);
}

openvdb::Vec3d
DeformationField::displacement(const openvdb::Vec3d& xWorld, ConstAccessor& acc) const
{
    openvdb::Coord v[4];
    double w[4];
    int axes[3];
    locate(xWorld, v, w, axes);
    openvdb::Vec3d u(0.0);
    for (int m = 0; m <= mDim; ++m) {
        if (w[m] == 0.0) continue;
        u += openvdb::Vec3d(acc.getValue(v[m])) * w[m];
    }
    return u;
}

openvdb::Mat3d
DeformationField::jacobian(const openvdb::Vec3d& xWorld) const
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
    return A;
}

double
DeformationField::jacobianDeterminant(const openvdb::Vec3d& xWorld) const
{
    const openvdb::Mat3d A = jacobian(xWorld);
    if (mDim == 2) return A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
    return A.det();
}

int
DeformationField::cellDeterminants(const openvdb::Coord& cell, double* dets) const
{
    ConstAccessor acc(mGrid->tree());
    const double invVoxel = 1.0 / mVoxelSize;
    const int corners = 1 << mDim;
    std::array<openvdb::Vec3d, 8> u;
    for (int c = 0; c < corners; ++c) {
        openvdb::Coord v = cell;
        if (mDim == 2) v[2] = mSliceK;
        for (int a = 0; a < mDim; ++a)
            v[a] += (c >> a) & 1;
        u[c] = openvdb::Vec3d(acc.getValue(v)) * invVoxel;
    }
    return cellDeterminants(mDim, u.data(), dets);
}

namespace {

/// det D phi on the Kuhn simplex of a unit cell whose path steps along axes a0, a1, a2 with
/// displacement differences d0, d1, d2: column a_m of D phi is e_{a_m} + d_m. The same
/// operations as the general loop of cellDeterminants().
inline double
pathDeterminant(const openvdb::Vec3d& d0, int a0, const openvdb::Vec3d& d1, int a1,
                const openvdb::Vec3d& d2, int a2)
{
    openvdb::Mat3d A = openvdb::Mat3d::identity();
    for (int r = 0; r < 3; ++r)
        A(r, a0) += d0[r];
    for (int r = 0; r < 3; ++r)
        A(r, a1) += d1[r];
    for (int r = 0; r < 3; ++r)
        A(r, a2) += d2[r];
    return A.det();
}

} // namespace

__attribute__((flatten)) int
DeformationField::cellDeterminants(int dimension, const openvdb::Vec3d* u, double* dets)
{
    if (dimension == 3) {
        // The six paths in the order of std::next_permutation from (0, 1, 2), as below, with
        // the twelve edge differences formed once (corner index bit a = step along axis a).
        const openvdb::Vec3d e10 = u[1] - u[0], e20 = u[2] - u[0], e40 = u[4] - u[0];
        const openvdb::Vec3d e31 = u[3] - u[1], e51 = u[5] - u[1], e32 = u[3] - u[2];
        const openvdb::Vec3d e62 = u[6] - u[2], e54 = u[5] - u[4], e64 = u[6] - u[4];
        const openvdb::Vec3d e73 = u[7] - u[3], e75 = u[7] - u[5], e76 = u[7] - u[6];
        dets[0] = pathDeterminant(e10, 0, e31, 1, e73, 2); // (0, 1, 2)
        dets[1] = pathDeterminant(e10, 0, e51, 2, e75, 1); // (0, 2, 1)
        dets[2] = pathDeterminant(e20, 1, e32, 0, e73, 2); // (1, 0, 2)
        dets[3] = pathDeterminant(e20, 1, e62, 2, e76, 0); // (1, 2, 0)
        dets[4] = pathDeterminant(e40, 2, e54, 0, e75, 1); // (2, 0, 1)
        dets[5] = pathDeterminant(e40, 2, e64, 1, e76, 0); // (2, 1, 0)
        return 6;
    }
    std::array<int, 3> order{{0, 1, 2}};
    int count = 0;
    do {
        // Path cell -> cell + e_order[0] -> ...: column order[m] of D phi is e + du.
        openvdb::Mat3d A = openvdb::Mat3d::identity();
        int mask = 0;
        for (int m = 0; m < dimension; ++m) {
            const int next = mask | (1 << order[m]);
            const openvdb::Vec3d du = u[next] - u[mask];
            for (int r = 0; r < dimension; ++r)
                A(r, order[m]) += du[r];
            mask = next;
        }
        dets[count++] = dimension == 2 ? A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0) : A.det();
    } while (std::next_permutation(order.begin(), order.begin() + dimension));
    return count;
}

DeformationField::InverseResult
DeformationField::inverse(const openvdb::Vec3d& yWorld) const
{
    ConstAccessor acc(mGrid->tree());
    return inverse(yWorld, acc);
}

DeformationField::InverseResult
DeformationField::inverse(const openvdb::Vec3d& yWorld, const openvdb::Vec3d& guessWorld) const
{
    ConstAccessor acc(mGrid->tree());
    return inverse(yWorld, guessWorld, acc);
}

DeformationField::InverseResult
DeformationField::inverse(const openvdb::Vec3d& yWorld, ConstAccessor& acc) const
{
    // Initial guess: two fixed-point iterates of x = y - u(x) (exact where u is locally
    // constant, and the walk makes up for the rest).
    openvdb::Vec3d x = yWorld - displacement(yWorld, acc);
    x = yWorld - displacement(x, acc);
    return inverse(yWorld, x, acc);
}

DeformationField::InverseResult
DeformationField::inverse(const openvdb::Vec3d& yWorld, const openvdb::Vec3d& guessWorld,
                          ConstAccessor& acc) const
{
    const openvdb::math::Transform& xform = mGrid->transform();
    const openvdb::Vec3d yIndex = xform.worldToIndex(yWorld);
    InverseResult r = inverseIndex(yIndex, xform.worldToIndex(guessWorld), acc);
    // As a displacement from y, so that phi^{-1}(y) = y exactly where phi = Id.
    r.x = yWorld + (r.x - yIndex) * mVoxelSize;
    r.residual *= mVoxelSize;
    if (mDim == 2) r.x[2] = yWorld[2];
    return r;
}

// flatten: locateIndex() and the accessor look-ups inlined into the walk (the same bits).
__attribute__((flatten)) DeformationField::InverseResult
DeformationField::inverseIndex(const openvdb::Vec3d& yIn, openvdb::Vec3d x,
                               ConstAccessor& acc) const
{
    // Nudge that picks the simplex the walk enters at a face (index units; coordinates are
    // below 2^13, whose spacing in double is ~1e-12).
    constexpr double NUDGE = 1e-9;
    // Steps allowed: a segment crosses O(its length in cells) simplices; 2^16 is far above any
    // walk from a guess inside the grid.
    constexpr int MAX_STEPS = 1 << 16;
    // Relative rate below which a barycentric coordinate counts as constant along the walk.
    constexpr double EXIT_TOLERANCE = 1e-10;
    const double toIndex = 1.0 / mVoxelSize;
    openvdb::Vec3d y = yIn;
    if (mDim == 2) {
        y[2] = mSliceK;
        x[2] = mSliceK;
    }
    InverseResult result;
    openvdb::Vec3d hint(0.0); // direction of the last move, unit length
    for (int step = 0; step < MAX_STEPS; ++step) {
        openvdb::Coord v[4];
        double w[4];
        int axes[3];
        kuhnLocate(mDim, mSliceK, x + hint * NUDGE, v, w, axes);
        ++result.simplices;
        // Barycentric coordinates of x in this simplex (the path order of the nudged point;
        // slightly negative ones are rounding) and the affine map phi(z) = z + sum lambda_m U_m.
        const openvdb::Vec3d t = x - openvdb::Vec3d(v[0].x(), v[0].y(), v[0].z());
        double lambda[4];
        lambda[0] = 1.0 - t[axes[0]];
        for (int m = 1; m < mDim; ++m)
            lambda[m] = t[axes[m - 1]] - t[axes[m]];
        lambda[mDim] = t[axes[mDim - 1]];
        openvdb::Vec3d U[4];
        openvdb::Vec3d q = x;
        for (int m = 0; m <= mDim; ++m) {
            U[m] = openvdb::Vec3d(acc.getValue(v[m])) * toIndex;
            q += U[m] * lambda[m];
        }
        openvdb::Mat3d A = openvdb::Mat3d::identity();
        for (int m = 1; m <= mDim; ++m) {
            const openvdb::Vec3d du = U[m] - U[m - 1];
            for (int row = 0; row < mDim; ++row)
                A(row, axes[m - 1]) += du[row];
        }
        const double det = mDim == 2 ? A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0) : A.det();
        if (!(det > 0.0)) {
            result.found = false;
            result.x = x;
            return result;
        }
        // The preimage of [q, y] in this simplex: x + s d, d = A^{-1} (y - q).
        const openvdb::Vec3d rhs = y - q;
        openvdb::Vec3d d(0.0);
        openvdb::Mat3d inverseA = openvdb::Mat3d::identity();
        if (mDim == 2) {
            d[0] = (A(1, 1) * rhs[0] - A(0, 1) * rhs[1]) / det;
            d[1] = (A(0, 0) * rhs[1] - A(1, 0) * rhs[0]) / det;
            inverseA(0, 0) = A(1, 1) / det;
            inverseA(0, 1) = -A(0, 1) / det;
            inverseA(1, 0) = -A(1, 0) / det;
            inverseA(1, 1) = A(0, 0) / det;
        } else {
            inverseA = A.inverse();
            d = inverseA * rhs;
        }
        // Rates of change of the barycentric coordinates along d, and the exit parameter.
        double mu[4];
        mu[0] = -d[axes[0]];
        for (int m = 1; m < mDim; ++m)
            mu[m] = d[axes[m - 1]] - d[axes[m]];
        mu[mDim] = d[axes[mDim - 1]];
        // A face whose coordinate decreases by less than EXIT_TOLERANCE |d| over the step is
        // not an exit: d lies in that face and the rate is rounding (without this a walk along
        // a face creeps forward by the nudge until it runs out of steps). Ignoring it moves the
        // point at most EXIT_TOLERANCE |d| outside the simplex.
        const double length = d.length();
        double s = 1.0;
        for (int m = 0; m <= mDim; ++m) {
            if (mu[m] < -EXIT_TOLERANCE * length) {
                s = std::min(s, std::max(lambda[m], 0.0) / -mu[m]);
            }
        }
        if (s >= 1.0 - 1e-12 || length <= NUDGE) {
            // y is in this simplex, or within the nudge of x (a walk through a vertex or an
            // edge, where the exit test sees rounding): the affine inverse of this simplex,
            // whose error is below |d| times the jump of D phi across the face.
            result.x = x + d;
            result.residual = (q + A * d - y).length();
            result.jacobian = inverseA;
            return result;
        }
        hint = d / length;
        if (s * length < NUDGE) {
            // At a face that the segment does not cross into this simplex (a degenerate
            // crossing through an edge or a vertex): step off it by the nudge.
            x += hint * NUDGE;
        } else {
            x += d * s;
        }
    }
    result.found = false;
    result.x = x;
    return result;
}

std::size_t
DeformationField::mapPoints(std::vector<openvdb::Vec3d>& points, bool inverse, bool threaded) const
{
    return mapPoints(points.data(), points.size(), inverse, threaded);
}

std::size_t
DeformationField::mapPoints(openvdb::Vec3d* points, std::size_t count, bool inverse,
                            bool threaded) const
{
    std::atomic<std::size_t> failed{0};
    auto body = [&](const tbb::blocked_range<std::size_t>& range) {
        std::size_t bad = 0;
        Cursor cursor(*this);
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            if (inverse) {
                const InverseResult r = cursor.inverse(points[i]);
                if (!r.found) ++bad;
                points[i] = r.x;
            } else {
                points[i] = cursor.apply(points[i]);
            }
        }
        failed += bad;
    };
    const tbb::blocked_range<std::size_t> all(0, count, 1024);
    if (threaded) {
        tbb::parallel_for(all, body);
    } else {
        body(all);
    }
    return failed;
}

} // namespace vdbmatch
