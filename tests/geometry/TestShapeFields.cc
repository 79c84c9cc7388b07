/// @file TestShapeFields.cc
/// @brief Tests of ShapeFields: the pointwise formulas of eq:defSi and
/// eq:regularizedGaussianCurvs, node fields of analytic shapes, stencil validity, input
/// validation, determinism and Hessian smoothing.
/// @see paper [eq:defSi], [eq:regularizedGaussianCurvs]

#include "support/AnalyticShapes.h"

#include <vdbmatch/geometry/ShapeFields.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>

using namespace vdbmatch;
using vdbmatch::test::AnalyticEllipsoid;
using vdbmatch::test::AnalyticSphere;

namespace {

constexpr Real TAU = 0.01;

template <int D>
Vec<D>
randomUnit(std::mt19937& rng)
{
    std::normal_distribution<Real> normal;
    Vec<D> v;
    for (int i = 0; i < D; ++i)
        v[i] = normal(rng);
    return v.normalized();
}

template <int D>
Mat<D>
randomSymmetric(std::mt19937& rng, Real scale)
{
    std::uniform_real_distribution<Real> uniform(-scale, scale);
    Mat<D> M;
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            M(i, j) = uniform(rng);
    return 0.5 * (M + M.transpose());
}

/// Deterministic noise in [-1, 1] from node coordinates (splitmix64 finalizer).
Real
hashNoise(int64_t i, int64_t j, int64_t k)
{
    uint64_t z = uint64_t(i) * 0x9E3779B97F4A7C15ull ^ uint64_t(j) * 0xC2B2AE3D27D4EB4Full ^
                 uint64_t(k) * 0x165667B19E3779F9ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    return 2.0 * Real(z >> 11) / Real(1ull << 53) - 1.0;
}

/// Max errors at the nodes with fields and |d| <= maxDistance: normal (angle-free |n - n*|),
/// tangential eigenvalues of S = R^2 against the offset curvatures, and |n^T S n - 1|.
struct NodeErrors
{
    Real normal = 0, curvature = 0, normalEigenvalue = 0;
    size_t count = 0;
};

template <int D, typename Shape>
NodeErrors
nodeErrors(const ShapeFields<D>& fields, const openvdb::FloatGrid& grid, const Shape& shape,
           Real maxDistance)
{
    NodeErrors e;
    const Real h = fields.voxelSize();
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const openvdb::Coord ijk = it.getCoord();
        if (D == 2 && ijk[2] != 0) continue;
        NodeFields<D> f;
        if (!fields.getNode(ijk, f)) continue;
        if (std::abs(f.d) > maxDistance) continue;
        Vec<D> x;
        for (int a = 0; a < D; ++a)
            x[a] = ijk[a] * h;
        const Vec<D> y = shape.closestPoint(x);
        const Real d = shape.signedDistance(x);
        const Mat<D> S = f.R * f.R;
        const auto kappa = test::offsetCurvatures<D>(shape.principalCurvatures(y), d);
        const auto lambda = test::tangentialEigenvalues<D>(S, f.n);
        e.normal = std::max(e.normal, (f.n - shape.normal(y)).norm());
        e.curvature = std::max(e.curvature, (lambda - kappa).cwiseAbs().maxCoeff());
        e.normalEigenvalue = std::max(e.normalEigenvalue, std::abs(f.n.dot(S * f.n) - 1.0));
        ++e.count;
    }
    return e;
}

} // namespace

////////////////////////////////////////////////////////////////////////////////
// Pointwise formulas

template <int D>
void
checkRegularizedShapeOperator()
{
    std::mt19937 rng(1234 + D);
    const Real tau = 0.05;
    for (int trial = 0; trial < 200; ++trial) {
        const Mat<D> H = randomSymmetric<D>(rng, 3.0);
        const Vec<D> n = randomUnit<D>(rng);
        const Mat<D> S = regularizedShapeOperator<D>(H, n, tau);
        const Mat<D> R = regularizedShapeOperatorSqrt<D>(H, n, tau);
        EXPECT_LT((S - S.transpose()).norm(), 1e-13);
        EXPECT_LT((R - R.transpose()).norm(), 1e-13);
        // n is an eigenvector with eigenvalue 1 (tau < 1).
        EXPECT_LT((S * n - n).norm(), 1e-12);
        EXPECT_LT((R * n - n).norm(), 1e-12);
        // Tangential eigenvalues: max(|eig(P H P)|, tau).
        const auto lambdaS = test::tangentialEigenvalues<D>(S, n);
        const test::TangentBasis<D> T = test::tangentBasis<D>(n);
        Eigen::Matrix<Real, D - 1, D - 1> HT = T.transpose() * H * T;
        Eigen::SelfAdjointEigenSolver<decltype(HT)> solver(HT, Eigen::EigenvaluesOnly);
        std::vector<Real> expected;
        for (int i = 0; i < D - 1; ++i)
            expected.push_back(std::max(std::abs(solver.eigenvalues()[i]), tau));
        std::sort(expected.begin(), expected.end());
        for (int i = 0; i < D - 1; ++i)
            EXPECT_NEAR(lambdaS[i], expected[size_t(i)], 1e-12);
        // R = S^{1/2}, and symmetricSqrt agrees.
        EXPECT_LT((R * R - S).norm(), 1e-12);
        EXPECT_LT((symmetricSqrt<D>(S) - R).norm(), 1e-12);
        // K = n^T cof(S) n = product of the tangential eigenvalues = det S / (n^T S n).
        const Real K = regularizedGaussianCurvature<D>(S, n);
        EXPECT_NEAR(K, lambdaS.prod(), 1e-12 * std::max(1.0, K));
        EXPECT_NEAR(K, S.determinant() / n.dot(S * n), 1e-12 * std::max(1.0, K));
    }
}

TEST(ShapeFieldsFormulas, RegularizedShapeOperator2D)
{
    checkRegularizedShapeOperator<2>();
}
TEST(ShapeFieldsFormulas, RegularizedShapeOperator3D)
{
    checkRegularizedShapeOperator<3>();
}

TEST(ShapeFieldsFormulas, RegularizationOfKnownMatrix)
{
    // D²d = diag(-2, 0.001, 0) with n = e_z: S = diag(|-2|, tau, 1) for tau = 0.01.
    Mat<3> H = Mat<3>::Zero();
    H(0, 0) = -2.0;
    H(1, 1) = 0.001;
    const Mat<3> S = regularizedShapeOperator<3>(H, Vec<3>::UnitZ(), TAU);
    Mat<3> expected = Mat<3>::Zero();
    expected.diagonal() << 2.0, TAU, 1.0;
    EXPECT_LT((S - expected).norm(), 1e-14);
    EXPECT_NEAR(regularizedGaussianCurvature<3>(S, Vec<3>::UnitZ()), 2.0 * TAU, 1e-14);
    // A Hessian with a normal component (discretization error) is projected away.
    H(0, 2) = H(2, 0) = 0.3;
    H(2, 2) = 0.2;
    EXPECT_LT((regularizedShapeOperator<3>(H, Vec<3>::UnitZ(), TAU) - expected).norm(), 1e-14);
}

////////////////////////////////////////////////////////////////////////////////
// Support library check

TEST(AnalyticShapes, EllipseDistanceMatchesDenseSearch)
{
    const AnalyticEllipsoid<2> ellipse(Vec<2>(0.5, 0.5), Vec<2>(0.3, 0.2));
    constexpr int SAMPLES = 200000;
    std::vector<Vec<2>> boundary(SAMPLES);
    for (int s = 0; s < SAMPLES; ++s) {
        const Real angle = 2.0 * M_PI * s / SAMPLES;
        boundary[size_t(s)] = ellipse.surfacePoint(Vec<2>(std::cos(angle), std::sin(angle)));
    }
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> uniform(0.1, 0.9);
    std::vector<Vec<2>> queries = {Vec<2>(0.5, 0.5), Vec<2>(0.5, 0.6), Vec<2>(0.7, 0.5),
                                   Vec<2>(0.55, 0.5), Vec<2>(0.5, 0.95)};
    for (int q = 0; q < 40; ++q)
        queries.emplace_back(uniform(rng), uniform(rng));
    for (const Vec<2>& x : queries) {
        Real best = INF;
        for (const Vec<2>& y : boundary)
            best = std::min(best, (x - y).norm());
        const Real d = ellipse.signedDistance(x);
        // Dense search is accurate to about (arc step)^2 / curvature radius.
        EXPECT_NEAR(std::abs(d), best, 1e-8) << x.transpose();
        const Vec<2> y = ellipse.closestPoint(x);
        const Vec<2> u = (y - ellipse.center()).cwiseQuotient(ellipse.semiAxes());
        EXPECT_NEAR(u.squaredNorm(), 1.0, 1e-12);
    }
    // Curvature of an ellipse at the end of the major axis: a / b^2.
    EXPECT_NEAR(ellipse.principalCurvatures(Vec<2>(0.8, 0.5))[0], 0.3 / (0.2 * 0.2), 1e-12);
    const AnalyticEllipsoid<3> ellipsoid(Vec<3>(0.5, 0.5, 0.5), Vec<3>(0.3, 0.25, 0.2));
    const auto k = ellipsoid.principalCurvatures(Vec<3>(0.8, 0.5, 0.5));
    EXPECT_NEAR(k[0], 0.3 / (0.25 * 0.25), 1e-12);
    EXPECT_NEAR(k[1], 0.3 / (0.2 * 0.2), 1e-12);
    // Points on symmetry planes, inside and outside.
    EXPECT_NEAR(ellipsoid.signedDistance(Vec<3>(0.5, 0.5, 0.5)), -0.2, 1e-14);
    EXPECT_NEAR(ellipsoid.signedDistance(Vec<3>(0.5, 0.5, 0.8)), 0.1, 1e-14);
    EXPECT_NEAR(ellipsoid.signedDistance(Vec<3>(0.9, 0.5, 0.5)), 0.1, 1e-14);
}

////////////////////////////////////////////////////////////////////////////////
// Node fields

TEST(ShapeFields, SphereNodeFields3D)
{
    const Vec<3> center(0.503, 0.488, 0.511);
    const AnalyticSphere<3> sphere(center, 0.3);
    const int level = 6;
    const auto grid = test::createSphereSdf(level, center, 0.3, test::DEFAULT_GRID_MARGIN, 5.0);
    ShapeFieldOptions opts;
    opts.tau = TAU;
    const ShapeFields<3> fields(*grid, opts);
    const Real h = fields.voxelSize();
    EXPECT_DOUBLE_EQ(h, 1.0 / 64.0);
    const NodeErrors e = nodeErrors<3>(fields, *grid, sphere, 2.0 * h);
    std::printf("sphere level %d nodes %zu: |n - n*| %.3g, curvature %.3g, |n.Sn - 1| %.3g\n",
                level, e.count, e.normal, e.curvature, e.normalEigenvalue);
    // Central differences: O(h^2) errors, about h^2 kappa^2 / 6 for n.
    EXPECT_GT(e.count, 10000u);
    EXPECT_LT(e.normal, 1e-3);
    EXPECT_LT(e.curvature, 0.01); // curvature 3.33
    EXPECT_LT(e.normalEigenvalue, 1e-6);
    // d is the grid value itself.
    auto acc = grid->getConstAccessor();
    NodeFields<3> f;
    const openvdb::Coord ijk(13, 31, 33); // |d| < 0.01 h
    ASSERT_TRUE(fields.getNode(ijk, f));
    EXPECT_EQ(f.d, Real(acc.getValue(ijk)));
}

TEST(ShapeFields, EllipseNodeFields2D)
{
    const Vec<2> center(0.497, 0.506);
    const Vec<2> axes(0.32, 0.22);
    const AnalyticEllipsoid<2> ellipse(center, axes);
    const auto grid = test::createEllipseSdf(7, center, axes, test::DEFAULT_GRID_MARGIN, 5.0);
    ShapeFieldOptions opts;
    opts.tau = TAU;
    const ShapeFields<2> fields(*grid, opts);
    const NodeErrors e = nodeErrors<2>(fields, *grid, ellipse, 2.0 * fields.voxelSize());
    std::printf("ellipse level 7 nodes %zu: |n - n*| %.3g, curvature %.3g, |n.Sn - 1| %.3g\n",
                e.count, e.normal, e.curvature, e.normalEigenvalue);
    EXPECT_GT(e.count, 500u);
    EXPECT_LT(e.normal, 1e-3);
    EXPECT_LT(e.curvature, 0.02); // curvatures 2.1 .. 6.6
    EXPECT_LT(e.normalEigenvalue, 1e-6);
}

/// A node has fields iff all voxels of its finite-difference stencil are active.
template <int D>
void
checkValidityFollowsActiveStencil(const openvdb::FloatGrid& grid)
{
    const ShapeFields<D> fields(grid, ShapeFieldOptions());
    auto acc = grid.getConstAccessor();
    size_t valid = 0, invalid = 0;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const openvdb::Coord ijk = it.getCoord();
        if (D == 2 && ijk[2] != 0) continue;
        bool complete = true;
        for (int a = 0; a < D; ++a) {
            for (int b = 0; b < D; ++b) {
                for (int sa = -1; sa <= 1; ++sa) {
                    for (int sb = -1; sb <= 1; ++sb) {
                        openvdb::Coord c = ijk;
                        c[a] += sa;
                        c[b] += (a == b ? 0 : sb);
                        complete = complete && acc.isValueOn(c);
                    }
                }
            }
        }
        NodeFields<D> f;
        EXPECT_EQ(fields.getNode(ijk, f), complete) << ijk;
        (complete ? valid : invalid) += 1;
    }
    EXPECT_EQ(fields.validNodeCount(), valid);
    EXPECT_GT(valid, 0u);
    EXPECT_GT(invalid, 0u);
    // Inactive voxels never get fields.
    NodeFields<D> f;
    EXPECT_FALSE(fields.getNode(openvdb::Coord(16, 16, 0), f)); // outside the band
}

TEST(ShapeFields, ValidityFollowsActiveStencil)
{
    checkValidityFollowsActiveStencil<3>(
        *test::createSphereSdf(5, Vec<3>(0.5, 0.5, 0.5), 0.3, test::DEFAULT_GRID_MARGIN, 3.0));
    checkValidityFollowsActiveStencil<2>(
        *test::createCircleSdf(5, Vec<2>(0.5, 0.5), 0.3, test::DEFAULT_GRID_MARGIN, 3.0));
}

TEST(ShapeFields, TwoDimensionalUsesOnlyTheZeroSlice)
{
    const auto grid = test::createCircleSdf(6, Vec<2>(0.5, 0.5), 0.3);
    const auto polluted = grid->deepCopy();
    auto acc = polluted->getAccessor();
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        acc.setValueOn(it.getCoord().offsetBy(0, 0, 1), 0.25f);
        acc.setValueOn(it.getCoord().offsetBy(0, 0, -1), -0.5f);
    }
    const ShapeFields<2> a(*grid, ShapeFieldOptions()), b(*polluted, ShapeFieldOptions());
    ASSERT_EQ(a.blockCount(), b.blockCount());
    for (size_t i = 0; i < a.blockCount(); ++i) {
        const size_t bytes =
            sizeof(float) * ShapeFields<2>::NUM_COMPONENTS * ShapeFields<2>::BLOCK_NODES;
        EXPECT_EQ(std::memcmp(a.blockValues(i), b.blockValues(i), bytes), 0);
    }
}

TEST(ShapeFields, SerialAndThreadedAreBitwiseEqual)
{
    const auto grid =
        test::createEllipsoidSdf(5, Vec<3>(0.5, 0.5, 0.5), Vec<3>(0.3, 0.25, 0.2), 3, 4.0);
    ShapeFieldOptions opts;
    opts.hessianSmoothing = 2;
    opts.threaded = false;
    const ShapeFields<3> serial(*grid, opts);
    opts.threaded = true;
    const ShapeFields<3> threaded(*grid, opts);
    ASSERT_EQ(serial.blockCount(), threaded.blockCount());
    const size_t bytes =
        sizeof(float) * ShapeFields<3>::NUM_COMPONENTS * ShapeFields<3>::BLOCK_NODES;
    for (size_t i = 0; i < serial.blockCount(); ++i) {
        EXPECT_EQ(serial.blockOrigin(i), threaded.blockOrigin(i));
        EXPECT_EQ(std::memcmp(serial.blockValues(i), threaded.blockValues(i), bytes), 0);
    }
}

TEST(ShapeFields, RejectsInvalidInput)
{
    const auto good = test::createSphereSdf(4, Vec<3>(0.5, 0.5, 0.5), 0.3);
    auto expectThrow = [](const openvdb::FloatGrid& grid, const ShapeFieldOptions& opts) {
        try {
            const ShapeFields<3> fields(grid, opts);
            ADD_FAILURE() << "no exception";
        } catch (const openvdb::ValueError& e) {
            EXPECT_NE(std::string(e.what()).find("ShapeFields"), std::string::npos) << e.what();
        }
    };
    {
        auto fog = good->deepCopy();
        fog->setGridClass(openvdb::GRID_FOG_VOLUME);
        expectThrow(*fog, ShapeFieldOptions());
    }
    {
        auto stretched = good->deepCopy();
        openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
        m.preScale(openvdb::Vec3d(1.0 / 16, 2.0 / 16, 1.0 / 16));
        stretched->setTransform(openvdb::math::Transform::createLinearTransform(m));
        expectThrow(*stretched, ShapeFieldOptions());
    }
    {
        auto shifted = good->deepCopy();
        shifted->transform().postTranslate(openvdb::Vec3d(0.5 / 16, 0.0, 0.0));
        expectThrow(*shifted, ShapeFieldOptions());
    }
    ShapeFieldOptions opts;
    opts.tau = 0.0;
    expectThrow(*good, opts);
    opts.tau = TAU;
    opts.hessianSmoothing = -1;
    expectThrow(*good, opts);
    opts.hessianSmoothing = 0;
    opts.hessianSmoothingLength = -1e-3;
    expectThrow(*good, opts);
    opts.hessianSmoothingLength = std::numeric_limits<Real>::quiet_NaN();
    expectThrow(*good, opts);
}

////////////////////////////////////////////////////////////////////////////////
// Hessian smoothing

TEST(ShapeFields, HessianSmoothingReducesCurvatureErrorOnNoisySdf)
{
    const Vec<3> center(0.503, 0.488, 0.511);
    const Real radius = 0.3;
    const AnalyticSphere<3> sphere(center, radius);
    const int level = 6;
    const Real h = 1.0 / (1 << level);
    constexpr Real NOISE = 1e-2; // amplitude in voxels
    const auto grid = test::createSdfGrid<3>(
        level,
        [&](const Vec<3>& x) {
            const Vec<3> ijk = x / h;
            return sphere.signedDistance(x) +
                   NOISE * h *
                       hashNoise(std::llround(ijk[0]), std::llround(ijk[1]), std::llround(ijk[2]));
        },
        test::DEFAULT_GRID_MARGIN, 8.0);
    ShapeFieldOptions opts;
    opts.tau = TAU;
    Real previous = INF;
    std::vector<Real> errors;
    for (int iterations : {0, 1, 2, 4}) {
        opts.hessianSmoothing = iterations;
        const ShapeFields<3> fields(*grid, opts);
        const NodeErrors e = nodeErrors<3>(fields, *grid, sphere, 1.5 * h);
        std::printf("noisy sphere, %d smoothing iterations: curvature error %.4g (of %.4g), "
                    "|n.Sn - 1| %.3g, %zu nodes\n",
                    iterations, e.curvature, 1.0 / radius, e.normalEigenvalue, e.count);
        EXPECT_GT(e.count, 5000u);
        EXPECT_LT(e.curvature, previous);
        previous = e.curvature;
        errors.push_back(e.curvature);
    }
    EXPECT_LT(errors[2], 0.25 * errors[0]);
    EXPECT_LT(errors[3], 0.1 * errors[0]);
}

TEST(ShapeFields, SmoothingLengthSetsThePassesPerVoxelSize)
{
    // n passes of [1,2,1]/4 have variance n h^2 / 2: n = round(2 s^2 / h^2), capped.
    ShapeFieldOptions opts;
    const double h = 1.0 / 64;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), 0);
    opts.hessianSmoothingLength = 0.49 * h;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), 0);
    opts.hessianSmoothingLength = h;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), 2);
    EXPECT_EQ(hessianSmoothingPasses(opts, 2 * h), 1); // one level coarser: 0.5 rounds to 1
    opts.hessianSmoothingLength = 2 * h;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), 8);
    EXPECT_EQ(hessianSmoothingPasses(opts, 2 * h), 2); // the same length: a quarter of the passes
    opts.hessianSmoothingLength = 100 * h;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), MAX_LENGTH_SMOOTHING_PASSES);
    opts.hessianSmoothing = 3; // fixed passes come on top
    opts.hessianSmoothingLength = h;
    EXPECT_EQ(hessianSmoothingPasses(opts, h), 5);
}

TEST(ShapeFields, SmoothingLengthIsTheSameAsItsPasses)
{
    const auto grid =
        test::createEllipsoidSdf(5, Vec<3>(0.5, 0.5, 0.5), Vec<3>(0.3, 0.25, 0.2), 3, 4.0);
    const double h = grid->voxelSize()[0];
    ShapeFieldOptions byLength, byCount, none;
    byLength.hessianSmoothingLength = h; // two passes at this grid
    byCount.hessianSmoothing = 2;
    const ShapeFields<3> a(*grid, byLength), b(*grid, byCount), c(*grid, none);
    ASSERT_EQ(a.blockCount(), b.blockCount());
    const size_t bytes =
        sizeof(float) * ShapeFields<3>::NUM_COMPONENTS * ShapeFields<3>::BLOCK_NODES;
    bool differsFromNone = false;
    for (size_t i = 0; i < a.blockCount(); ++i) {
        EXPECT_EQ(std::memcmp(a.blockValues(i), b.blockValues(i), bytes), 0);
        differsFromNone |= std::memcmp(a.blockValues(i), c.blockValues(i), bytes) != 0;
    }
    EXPECT_TRUE(differsFromNone);
}
