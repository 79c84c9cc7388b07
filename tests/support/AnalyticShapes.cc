/// @file AnalyticShapes.cc
/// @brief Closest points on ellipsoids, analytic curvatures and level-set grid generation.

#include "support/AnalyticShapes.h"

#include <Eigen/Eigenvalues>
#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

namespace vdbmatch {
namespace test {

namespace {

/// Iteration cap of the safeguarded Newton solve; it converges in far fewer steps.
constexpr int MAX_ROOT_ITERATIONS = 200;

/// Closest point of the point z (all z_i >= 0) on the ellipsoid with semi-axes e (sorted
/// descending), restricted to the first m coordinates. Eberly, "Distance from a point to an
/// ellipse, an ellipsoid, or a hyperellipsoid" (2013), with Newton instead of bisection.
void
closestPointSorted(const Real* e, const Real* z, int m, Real* y)
{
    if (m == 1) {
        y[0] = e[0];
        return;
    }
    const Real eLast = e[m - 1];
    if (z[m - 1] > 0.0) {
        // Root of F(t) = sum_i (e_i z_i / (t + e_i^2))^2 - 1, decreasing and convex on
        // (-eLast^2, inf); F(lo) >= 0 >= F(hi).
        Real norm2 = 0.0;
        for (int i = 0; i < m; ++i)
            norm2 += (e[i] * z[i]) * (e[i] * z[i]);
        Real lo = -eLast * eLast + eLast * z[m - 1];
        Real hi = -eLast * eLast + std::sqrt(norm2);
        Real t = lo;
        for (int iter = 0; iter < MAX_ROOT_ITERATIONS; ++iter) {
            Real f = -1.0, df = 0.0;
            for (int i = 0; i < m; ++i) {
                const Real q = e[i] * z[i] / (t + e[i] * e[i]);
                f += q * q;
                df -= 2.0 * q * q / (t + e[i] * e[i]);
            }
            if (f > 0.0) {
                lo = t;
            } else if (f < 0.0) {
                hi = t;
            } else {
                break;
            }
            const Real newton = df < 0.0 ? t - f / df : lo;
            const Real next = (newton > lo && newton < hi) ? newton : 0.5 * (lo + hi);
            if (next == t || !(hi > lo)) break;
            t = next;
        }
        for (int i = 0; i < m; ++i)
            y[i] = e[i] * e[i] * z[i] / (t + e[i] * e[i]);
        return;
    }
    // z_{m-1} = 0: the closest point leaves the plane y_{m-1} = 0 only if the candidate of the
    // limit t = -eLast^2 lies inside the (m-1)-dimensional section.
    std::array<Real, 3> candidate{{0.0, 0.0, 0.0}};
    bool feasible = true;
    Real sum = 0.0;
    for (int i = 0; i < m - 1 && feasible; ++i) {
        if (z[i] == 0.0) continue;
        const Real denom = e[i] * e[i] - eLast * eLast;
        if (!(denom > 0.0)) {
            feasible = false;
            break;
        }
        candidate[i] = e[i] * e[i] * z[i] / denom;
        sum += (candidate[i] / e[i]) * (candidate[i] / e[i]);
    }
    if (feasible && sum < 1.0) {
        for (int i = 0; i < m - 1; ++i)
            y[i] = candidate[i];
        y[m - 1] = eLast * std::sqrt(1.0 - sum);
        return;
    }
    y[m - 1] = 0.0;
    closestPointSorted(e, z, m - 1, y);
}

} // namespace

template <int D>
TangentBasis<D>
tangentBasis(const Vec<D>& n)
{
    TangentBasis<D> T;
    if constexpr (D == 2) {
        T << -n[1], n[0];
    } else {
        int axis = 0;
        n.cwiseAbs().minCoeff(&axis);
        const Vec<3> t0 = n.cross(Vec<3>::Unit(axis)).normalized();
        T.col(0) = t0;
        T.col(1) = n.cross(t0);
    }
    return T;
}

template <int D>
Curvatures<D>
offsetCurvatures(const Curvatures<D>& kappa, Real d)
{
    Curvatures<D> k;
    for (int i = 0; i < D - 1; ++i)
        k[i] = kappa[i] / (1.0 + kappa[i] * d);
    return k;
}

template <int D>
Curvatures<D>
tangentialEigenvalues(const Mat<D>& S, const Vec<D>& n)
{
    const TangentBasis<D> T = tangentBasis<D>(n.normalized());
    using TangentMat = Eigen::Matrix<Real, D - 1, D - 1>;
    const TangentMat M = T.transpose() * S * T;
    Eigen::SelfAdjointEigenSolver<TangentMat> solver(Real(0.5) * (M + M.transpose()),
                                                     Eigen::EigenvaluesOnly);
    return solver.eigenvalues();
}

template <int D>
Vec<D>
AnalyticSphere<D>::closestPoint(const Vec<D>& x) const
{
    return mCenter + mRadius * (x - mCenter).normalized();
}

template <int D>
Vec<D>
AnalyticEllipsoid<D>::closestPoint(const Vec<D>& x) const
{
    std::array<int, D> perm;
    std::iota(perm.begin(), perm.end(), 0);
    std::stable_sort(perm.begin(), perm.end(),
                     [&](int i, int j) { return mSemiAxes[i] > mSemiAxes[j]; });
    std::array<Real, D> e, z, y;
    for (int i = 0; i < D; ++i) {
        e[i] = mSemiAxes[perm[i]];
        z[i] = std::abs(x[perm[i]] - mCenter[perm[i]]);
    }
    closestPointSorted(e.data(), z.data(), D, y.data());
    Vec<D> result;
    for (int i = 0; i < D; ++i) {
        const int a = perm[i];
        result[a] = mCenter[a] + std::copysign(y[i], x[a] - mCenter[a]);
    }
    return result;
}

template <int D>
Real
AnalyticEllipsoid<D>::signedDistance(const Vec<D>& x) const
{
    const Vec<D> u = (x - mCenter).cwiseQuotient(mSemiAxes);
    const Real dist = (x - closestPoint(x)).norm();
    return u.squaredNorm() < 1.0 ? -dist : dist;
}

template <int D>
Vec<D>
AnalyticEllipsoid<D>::normal(const Vec<D>& y) const
{
    return (y - mCenter).cwiseQuotient(mSemiAxes.cwiseProduct(mSemiAxes)).normalized();
}

template <int D>
Curvatures<D>
AnalyticEllipsoid<D>::principalCurvatures(const Vec<D>& y) const
{
    const Vec<D> invA2 = mSemiAxes.cwiseProduct(mSemiAxes).cwiseInverse();
    const Vec<D> g = (y - mCenter).cwiseProduct(invA2);
    const TangentBasis<D> T = tangentBasis<D>(g.normalized());
    using TangentMat = Eigen::Matrix<Real, D - 1, D - 1>;
    const TangentMat M = T.transpose() * invA2.asDiagonal() * T / g.norm();
    Eigen::SelfAdjointEigenSolver<TangentMat> solver(M, Eigen::EigenvaluesOnly);
    return solver.eigenvalues();
}

template <int D>
Vec<D>
AnalyticEllipsoid<D>::surfacePoint(const Vec<D>& direction) const
{
    return mCenter + mSemiAxes.cwiseProduct(direction.normalized());
}

template <int D>
openvdb::FloatGrid::Ptr
createSdfGrid(int level, const std::function<Real(const Vec<D>&)>& sdf, int margin,
              Real halfWidthVoxels)
{
    using openvdb::Coord;
    using LeafT = openvdb::FloatTree::LeafNodeType;
    const int n = 1 << level;
    const double h = 1.0 / double(n);
    const int lo = -margin, hi = n + margin;
    const int leafDim = int(LeafT::DIM);
    const int firstOrigin = (lo >= 0 ? lo / leafDim : -((-lo + leafDim - 1) / leafDim)) * leafDim;

    std::vector<Coord> origins;
    for (int z = (D == 3 ? firstOrigin : 0); z <= (D == 3 ? hi : 0); z += leafDim)
        for (int y = firstOrigin; y <= hi; y += leafDim)
            for (int x = firstOrigin; x <= hi; x += leafDim)
                origins.emplace_back(x, y, z);

    const float background = SDF_BACKGROUND;
    const Real band = halfWidthVoxels * h;
    std::vector<std::unique_ptr<LeafT>> leaves(origins.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, origins.size()), [&](const auto& range) {
        for (size_t b = range.begin(); b != range.end(); ++b) {
            auto leaf = std::make_unique<LeafT>(origins[b], background, false);
            bool anyActive = false;
            for (auto it = leaf->beginValueAll(); it; ++it) {
                const Coord ijk = it.getCoord();
                if (D == 2 && ijk[2] != 0) continue;
                bool inRange = true;
                for (int a = 0; a < D; ++a)
                    inRange = inRange && ijk[a] >= lo && ijk[a] <= hi;
                if (!inRange) continue;
                Vec<D> x;
                for (int a = 0; a < D; ++a)
                    x[a] = double(ijk[a]) * h;
                const Real d = sdf(x);
                if (std::abs(d) <= band) {
                    it.setValue(float(d));
                    it.setValueOn(true);
                    anyActive = true;
                } else {
                    it.setValue(d < 0.0 ? -background : background);
                }
            }
            if (anyActive) leaves[b] = std::move(leaf);
        }
    });

    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(background);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    for (auto& leaf : leaves) {
        if (leaf) grid->tree().addLeaf(leaf.release());
    }
    openvdb::tools::signedFloodFill(grid->tree());
    return grid;
}

openvdb::FloatGrid::Ptr
createSphereSdf(int level, const Vec<3>& center, Real radius, int margin, Real halfWidthVoxels)
{
    const AnalyticSphere<3> shape(center, radius);
    return createSdfGrid<3>(
        level, [&](const Vec<3>& x) { return shape.signedDistance(x); }, margin, halfWidthVoxels);
}

openvdb::FloatGrid::Ptr
createCircleSdf(int level, const Vec<2>& center, Real radius, int margin, Real halfWidthVoxels)
{
    const AnalyticSphere<2> shape(center, radius);
    return createSdfGrid<2>(
        level, [&](const Vec<2>& x) { return shape.signedDistance(x); }, margin, halfWidthVoxels);
}

openvdb::FloatGrid::Ptr
createEllipsoidSdf(int level, const Vec<3>& center, const Vec<3>& semiAxes, int margin,
                   Real halfWidthVoxels)
{
    const AnalyticEllipsoid<3> shape(center, semiAxes);
    return createSdfGrid<3>(
        level, [&](const Vec<3>& x) { return shape.signedDistance(x); }, margin, halfWidthVoxels);
}

openvdb::FloatGrid::Ptr
createEllipseSdf(int level, const Vec<2>& center, const Vec<2>& semiAxes, int margin,
                 Real halfWidthVoxels)
{
    const AnalyticEllipsoid<2> shape(center, semiAxes);
    return createSdfGrid<2>(
        level, [&](const Vec<2>& x) { return shape.signedDistance(x); }, margin, halfWidthVoxels);
}

template TangentBasis<2> tangentBasis<2>(const Vec<2>&);
template TangentBasis<3> tangentBasis<3>(const Vec<3>&);
template Curvatures<2> tangentialEigenvalues<2>(const Mat<2>&, const Vec<2>&);
template Curvatures<3> tangentialEigenvalues<3>(const Mat<3>&, const Vec<3>&);
template Curvatures<2> offsetCurvatures<2>(const Curvatures<2>&, Real);
template Curvatures<3> offsetCurvatures<3>(const Curvatures<3>&, Real);
template openvdb::FloatGrid::Ptr createSdfGrid<2>(int, const std::function<Real(const Vec<2>&)>&,
                                                  int, Real);
template openvdb::FloatGrid::Ptr createSdfGrid<3>(int, const std::function<Real(const Vec<3>&)>&,
                                                  int, Real);
template class AnalyticSphere<2>;
template class AnalyticSphere<3>;
template class AnalyticEllipsoid<2>;
template class AnalyticEllipsoid<3>;

} // namespace test
} // namespace vdbmatch
