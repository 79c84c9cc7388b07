/// @file TestFieldSampler.cc
/// @brief Tests of FieldSampler: exactness of the quadratic quasi-interpolant on linear and
/// quadratic data, C¹ continuity across knots, derivatives against finite differences,
/// sampleDistance == sample().d, tier fallback, and convergence of n and of the curvatures
/// read off S = R² on spheres, circles, ellipsoids and ellipses.
/// @see paper [eq:defSi]

#include "support/AnalyticShapes.h"

#include <vdbmatch/geometry/FieldSampler.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace vdbmatch;
using vdbmatch::test::AnalyticEllipsoid;
using vdbmatch::test::AnalyticSphere;

namespace {

constexpr Real TAU = 0.01;

template <int D>
Vec<D>
randomPoint(std::mt19937& rng, Real lo, Real hi)
{
    std::uniform_real_distribution<Real> uniform(lo, hi);
    Vec<D> x;
    for (int a = 0; a < D; ++a)
        x[a] = uniform(rng);
    return x;
}

template <int D>
Vec<D>
randomUnit(std::mt19937& rng)
{
    std::normal_distribution<Real> normal;
    Vec<D> v;
    for (int a = 0; a < D; ++a)
        v[a] = normal(rng);
    return v.normalized();
}

template <int D>
ShapeFieldOptions
smallTau()
{
    ShapeFieldOptions opts;
    opts.tau = TAU;
    return opts;
}

/// All interpolated components as one vector: d, n, R (full matrix, row-major).
template <int D>
Eigen::VectorXd
flatten(const RawFields<D>& f)
{
    Eigen::VectorXd v(1 + D + D * D);
    v[0] = f.d;
    for (int i = 0; i < D; ++i)
        v[1 + i] = f.n[i];
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            v[1 + D + i * D + j] = f.R(i, j);
    return v;
}

/// Derivatives along axis k in the layout of flatten().
template <int D>
Eigen::VectorXd
flattenDerivative(const RawFieldDerivatives<D>& g, int k)
{
    Eigen::VectorXd v(1 + D + D * D);
    v[0] = g.dd[k];
    for (int i = 0; i < D; ++i)
        v[1 + i] = g.dn(i, k);
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            v[1 + D + i * D + j] = g.dR[k](i, j);
    return v;
}

template <int D>
typename FieldSampler<D>::Ptr
makeSampler(const openvdb::FloatGrid::Ptr& grid, const ShapeFieldOptions& opts = smallTau<D>())
{
    return FieldSampler<D>::build({grid}, opts);
}

} // namespace

////////////////////////////////////////////////////////////////////////////////
// Exactness of the interpolant

/// d = a.x + c with node values exactly representable in float: d and ∇d are reproduced to
/// rounding, n is constant, and R = n⊗n + sqrt(tau) P (D²d = 0).
template <int D>
void
checkLinearReproduction()
{
    Vec<D> a;
    if constexpr (D == 3) {
        a << 0.5, -0.25, 0.125;
    } else {
        a << 0.5, -0.25;
    }
    const Real c = -0.375;
    const auto grid = test::createSdfGrid<D>(5, [&](const Vec<D>& x) { return a.dot(x) + c; });
    const auto sampler = makeSampler<D>(grid);
    const Vec<D> n = a.normalized();
    const Mat<D> P = Mat<D>::Identity() - n * n.transpose();
    const Mat<D> expectedR = n * n.transpose() + std::sqrt(TAU) * P;
    std::mt19937 rng(11);
    for (int trial = 0; trial < 500; ++trial) {
        const Vec<D> x = randomPoint<D>(rng, 0.0, 1.0);
        RawFields<D> f;
        RawFieldDerivatives<D> g;
        ASSERT_TRUE(sampler->sample(x, f, &g)) << x.transpose();
        EXPECT_NEAR(f.d, a.dot(x) + c, 1e-14);
        EXPECT_LT((g.dd - a).norm(), 1e-13);
        EXPECT_LT((f.n - n).norm(), 1e-7);
        EXPECT_LT(g.dn.norm(), 1e-12);
        EXPECT_LT((f.R - expectedR).norm(), 1e-6);
        for (int k = 0; k < D; ++k)
            EXPECT_LT(g.dR[k].norm(), 1e-12);
    }
}

TEST(FieldSampler, ReproducesLinearFunctions2D)
{
    checkLinearReproduction<2>();
}
TEST(FieldSampler, ReproducesLinearFunctions3D)
{
    checkLinearReproduction<3>();
}

/// Schoenberg's operator maps x_a^2 to x_a^2 + h^2/4 and reproduces bilinear terms: this pins
/// the weights down (any other quadratic-spline weights fail).
template <int D>
void
checkQuadraticData()
{
    const int level = 5;
    const Real h = 1.0 / (1 << level);
    // Gradient never vanishes in the box, node values are exact in float.
    auto f = [](const Vec<D>& x) {
        if constexpr (D == 3) {
            return (x[0] + 0.25) * (x[0] + 0.25) + (x[1] + 0.125) * (x[2] + 0.5) + 2.0 * x[2];
        } else {
            return (x[0] + 0.25) * (x[0] + 0.25) + (x[0] + 0.5) * (x[1] + 0.125) + 2.0 * x[1];
        }
    };
    auto gradient = [](const Vec<D>& x) {
        Vec<D> g;
        if constexpr (D == 3) {
            g << 2.0 * (x[0] + 0.25), x[2] + 0.5, x[1] + 0.125 + 2.0;
        } else {
            g << 2.0 * (x[0] + 0.25) + x[1] + 0.125, x[0] + 0.5 + 2.0;
        }
        return g;
    };
    const auto grid = test::createSdfGrid<D>(level, [&](const Vec<D>& x) { return f(x); });
    const auto sampler = makeSampler<D>(grid);
    std::mt19937 rng(12);
    for (int trial = 0; trial < 500; ++trial) {
        const Vec<D> x = randomPoint<D>(rng, 0.0, 1.0);
        RawFields<D> s;
        RawFieldDerivatives<D> g;
        ASSERT_TRUE(sampler->sample(x, s, &g));
        EXPECT_NEAR(s.d, f(x) + 0.25 * h * h, 1e-13);
        EXPECT_LT((g.dd - gradient(x)).norm(), 1e-12);
    }
}

TEST(FieldSampler, QuadraticDataGivesSchoenbergShift2D)
{
    checkQuadraticData<2>();
}
TEST(FieldSampler, QuadraticDataGivesSchoenbergShift3D)
{
    checkQuadraticData<3>();
}

////////////////////////////////////////////////////////////////////////////////
// Smoothness and derivatives on curved data

/// Values and derivatives of all fields are continuous across the knot planes (half-integer
/// node coordinates) where the stencil switches.
template <int D>
void
checkC1AcrossKnots(const openvdb::FloatGrid::Ptr& grid, const Vec<D>& center, Real radius)
{
    const auto sampler = makeSampler<D>(grid);
    const Real h = sampler->voxelSize(0);
    const Real delta = 1e-9 * h;
    std::mt19937 rng(21);
    std::uniform_real_distribution<Real> offset(-1.5, 1.5);
    int checked = 0;
    Real maxValueJump = 0, maxDerivativeJump = 0;
    for (int trial = 0; trial < 300; ++trial) {
        Vec<D> x = center + (radius + offset(rng) * h) * randomUnit<D>(rng);
        const int axis = trial % D;
        x[axis] = (std::floor(x[axis] / h) + 0.5) * h; // on a knot plane
        Vec<D> xm = x, xp = x;
        xm[axis] -= delta;
        xp[axis] += delta;
        RawFields<D> fm, fp;
        RawFieldDerivatives<D> gm, gp;
        if (!sampler->sample(xm, fm, &gm) || !sampler->sample(xp, fp, &gp)) continue;
        ++checked;
        const Eigen::VectorXd vm = flatten<D>(fm), vp = flatten<D>(fp);
        maxValueJump = std::max(maxValueJump, (vp - vm).cwiseAbs().maxCoeff());
        for (int k = 0; k < D; ++k) {
            const Eigen::VectorXd dm = flattenDerivative<D>(gm, k);
            const Eigen::VectorXd dp = flattenDerivative<D>(gp, k);
            const Real scale = std::max(1.0, dm.cwiseAbs().maxCoeff());
            maxDerivativeJump =
                std::max(maxDerivativeJump, (dp - dm).cwiseAbs().maxCoeff() / scale);
        }
    }
    std::printf("C1 check (%dD): %d knot points, max value jump %.3g, max rel. derivative jump "
                "%.3g\n",
                D, checked, maxValueJump, maxDerivativeJump);
    EXPECT_GT(checked, 250);
    // Jumps are O(delta); a C0 interpolant would give derivative jumps of O(h |f''|) ~ 1e-2.
    EXPECT_LT(maxValueJump, 1e-8);
    EXPECT_LT(maxDerivativeJump, 1e-6);
}

TEST(FieldSampler, IsC1AcrossKnots2D)
{
    checkC1AcrossKnots<2>(test::createCircleSdf(6, Vec<2>(0.5, 0.5), 0.3), Vec<2>(0.5, 0.5), 0.3);
}

TEST(FieldSampler, IsC1AcrossKnots3D)
{
    const Vec<3> c(0.5, 0.5, 0.5);
    checkC1AcrossKnots<3>(test::createSphereSdf(5, c, 0.3, test::DEFAULT_GRID_MARGIN, 5.0), c, 0.3);
}

/// Derivatives equal central differences of the sampled values, and sampleDistance equals
/// sample().d bitwise.
template <int D, typename Shape>
void
checkDerivatives(const openvdb::FloatGrid::Ptr& grid, const Shape& shape)
{
    const auto sampler = makeSampler<D>(grid);
    const Real h = sampler->voxelSize(0);
    const Real eps = 1e-6 * h;
    std::mt19937 rng(31);
    std::uniform_real_distribution<Real> offset(-2.0, 2.0);
    int checked = 0;
    Real maxRelError = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const Vec<D> y = shape.surfacePoint(randomUnit<D>(rng));
        const Vec<D> x = y + offset(rng) * h * shape.normal(y);
        RawFields<D> f, fNoDeriv;
        RawFieldDerivatives<D> g;
        if (!sampler->sample(x, f, &g)) continue;
        ASSERT_TRUE(sampler->sample(x, fNoDeriv, nullptr));
        Real d = 0;
        ASSERT_TRUE(sampler->sampleDistance(x, d));
        EXPECT_EQ(d, f.d);        // bitwise
        EXPECT_EQ(d, fNoDeriv.d); // bitwise
        EXPECT_EQ(flatten<D>(f), flatten<D>(fNoDeriv));
        for (int k = 0; k < D; ++k) {
            Vec<D> xp = x, xm = x;
            xp[k] += eps;
            xm[k] -= eps;
            RawFields<D> fp, fm;
            ASSERT_TRUE(sampler->sample(xp, fp, nullptr));
            ASSERT_TRUE(sampler->sample(xm, fm, nullptr));
            const Eigen::VectorXd fd = (flatten<D>(fp) - flatten<D>(fm)) / (2.0 * eps);
            const Eigen::VectorXd an = flattenDerivative<D>(g, k);
            const Real scale = std::max(1.0, an.cwiseAbs().maxCoeff());
            const Real err = (fd - an).cwiseAbs().maxCoeff() / scale;
            maxRelError = std::max(maxRelError, err);
            EXPECT_LE(err, 1e-6) << "axis " << k << " at " << x.transpose();
        }
        ++checked;
    }
    std::printf("derivative check (%dD): %d points, max rel. error vs central differences %.3g\n",
                D, checked, maxRelError);
    EXPECT_GT(checked, 250);
}

TEST(FieldSampler, DerivativesMatchFiniteDifferences2D)
{
    const AnalyticEllipsoid<2> ellipse(Vec<2>(0.5, 0.5), Vec<2>(0.32, 0.22));
    checkDerivatives<2>(test::createEllipseSdf(6, ellipse.center(), ellipse.semiAxes(), 3, 5.0),
                        ellipse);
}

TEST(FieldSampler, DerivativesMatchFiniteDifferences3D)
{
    const AnalyticEllipsoid<3> ellipsoid(Vec<3>(0.5, 0.5, 0.5), Vec<3>(0.32, 0.25, 0.2));
    checkDerivatives<3>(
        test::createEllipsoidSdf(5, ellipsoid.center(), ellipsoid.semiAxes(), 3, 5.0), ellipsoid);
}

////////////////////////////////////////////////////////////////////////////////
// Tiers

template <int D>
void
checkTierFallback()
{
    Vec<D> center = Vec<D>::Constant(0.5);
    const Real radius = 0.3;
    // Fine (h = 1/64): narrow band of half width 4 voxels; coarse (h = 1/16): all nodes of
    // [-3h, 1 + 3h]^D.
    const auto fine = test::createSdfGrid<D>(
        6, [&](const Vec<D>& x) { return (x - center).norm() - radius; }, 3, 4.0);
    const auto coarse = test::createSdfGrid<D>(
        4, [&](const Vec<D>& x) { return (x - center).norm() - radius; }, 3);
    const auto both = FieldSampler<D>::build({fine, coarse}, smallTau<D>());
    const auto fineOnly = makeSampler<D>(fine);
    const auto coarseOnly = makeSampler<D>(coarse);
    ASSERT_EQ(both->tierCount(), 2u);
    EXPECT_GT(both->blockCount(0), both->blockCount(1));

    Vec<D> nearSurface = center;
    nearSurface[0] += radius + 0.001;
    // Beyond the fine band, and more than 1.5 coarse voxels from the kink at the centre.
    Vec<D> farInside = center;
    farInside[0] += 0.15;
    Vec<D> outsideBox = Vec<D>::Constant(1.5);
    Vec<D> notFinite = Vec<D>::Constant(std::numeric_limits<Real>::quiet_NaN());

    RawFields<D> f, ref;
    Real d = 0, dRef = 0;
    EXPECT_EQ(both->findTier(nearSurface), 0);
    ASSERT_TRUE(both->sample(nearSurface, f, nullptr));
    ASSERT_TRUE(fineOnly->sample(nearSurface, ref, nullptr));
    EXPECT_EQ(flatten<D>(f), flatten<D>(ref));
    // Schoenberg's operator is not interpolating: d is shifted by about (h^2/8) Δd.
    EXPECT_NEAR(f.d, 0.001, 3e-4);

    EXPECT_EQ(both->findTier(farInside), 1);
    EXPECT_FALSE(fineOnly->sampleDistance(farInside, dRef));
    ASSERT_TRUE(both->sample(farInside, f, nullptr));
    ASSERT_TRUE(coarseOnly->sample(farInside, ref, nullptr));
    EXPECT_EQ(flatten<D>(f), flatten<D>(ref));
    ASSERT_TRUE(both->sampleDistance(farInside, d));
    EXPECT_EQ(d, ref.d);
    EXPECT_NEAR(d, -0.15, 0.01); // coarse tier, h = 1/16

    // The tier-reporting sampleDistance, and sameStencil (Energy's kept inverse-band samples):
    // the same tier and stencil exactly when every tier up to the one used rounds both points to
    // the same node.
    for (const Vec<D>& x : {nearSurface, farInside}) {
        int tier = -1;
        ASSERT_TRUE(both->sampleDistance(x, dRef, tier));
        ASSERT_TRUE(both->sampleDistance(x, d));
        EXPECT_EQ(d, dRef);
        EXPECT_EQ(tier, both->findTier(x));
        Vec<D> nudged = x;
        nudged[1] += 1e-4;
        EXPECT_TRUE(both->sameStencil(nudged, x, tier));
        EXPECT_FALSE(both->sameStencil(nudged, x, -1));
        EXPECT_FALSE(both->sameStencil(nudged, x, 2));
        EXPECT_FALSE(both->sameStencil(notFinite, x, tier));
    }
    // nearSurface rounds to fine node 51 along x (h = 1/64); 0.805 rounds to 52.
    Vec<D> acrossFine = nearSurface;
    acrossFine[0] = 0.805;
    EXPECT_FALSE(both->sameStencil(acrossFine, nearSurface, 0));
    // farInside (x = 0.65) rounds to coarse node 10 (h = 1/16) and fine node 42; 0.655 to the
    // same two; 0.648 to coarse node 10 but fine node 41: a finer tier's rounding decides as
    // well, since its stencil could be complete there.
    Vec<D> sameCoarse = farInside, acrossFineOnly = farInside;
    sameCoarse[0] = 0.655;
    acrossFineOnly[0] = 0.648;
    EXPECT_TRUE(both->sameStencil(sameCoarse, farInside, 1));
    EXPECT_FALSE(both->sameStencil(acrossFineOnly, farInside, 1));
    EXPECT_TRUE(coarseOnly->sameStencil(acrossFineOnly, farInside, 0));

    for (const Vec<D>& x : {outsideBox, notFinite}) {
        EXPECT_EQ(both->findTier(x), -1);
        EXPECT_FALSE(both->sampleDistance(x, d));
        EXPECT_FALSE(both->sample(x, f, nullptr));
    }
    const FieldSampler<D> empty;
    EXPECT_FALSE(empty.sampleDistance(center, d));

    // Tiers out of order are rejected.
    EXPECT_THROW(FieldSampler<D>::build({coarse, fine}, smallTau<D>()), openvdb::ValueError);
    EXPECT_THROW(FieldSampler<D>::build({fine, nullptr}, smallTau<D>()), openvdb::ValueError);
}

TEST(FieldSampler, FallsBackToCoarserTiers2D)
{
    checkTierFallback<2>();
}
TEST(FieldSampler, FallsBackToCoarserTiers3D)
{
    checkTierFallback<3>();
}

TEST(FieldSampler, ThreadedAndSerialBuildsAgree)
{
    const auto grid = test::createSphereSdf(5, Vec<3>(0.5, 0.5, 0.5), 0.3, 3, 4.0);
    ShapeFieldOptions opts = smallTau<3>();
    opts.threaded = false;
    const auto serial = makeSampler<3>(grid, opts);
    opts.threaded = true;
    const auto threaded = makeSampler<3>(grid, opts);
    std::mt19937 rng(41);
    for (int trial = 0; trial < 200; ++trial) {
        const Vec<3> x =
            Vec<3>::Constant(0.5) + (0.3 + 0.02 * (trial % 5 - 2)) * randomUnit<3>(rng);
        RawFields<3> a, b;
        const bool okA = serial->sample(x, a, nullptr), okB = threaded->sample(x, b, nullptr);
        ASSERT_EQ(okA, okB);
        if (okA) {
            EXPECT_EQ(flatten<3>(a), flatten<3>(b));
        }
    }
}

////////////////////////////////////////////////////////////////////////////////
// Convergence of the geometry read off the sampled fields

struct LevelErrors
{
    int level;
    Real normal, curvature, normalEigenvalue;
};

/// Max errors over fixed points near the surface (|d| <= h_5 / 2): |n/|n| - n*|, tangential
/// eigenvalues of S = R^2 against the offset-surface curvatures κ/(1 + κ d) (relative to the
/// largest curvature of the shape), and |n^T S n - 1|.
template <int D, typename Shape>
std::vector<LevelErrors>
convergence(const char* name, const Shape& shape, Real maxCurvature,
            const std::function<openvdb::FloatGrid::Ptr(int)>& makeGrid)
{
    constexpr int POINTS = 400;
    const Real offsetRange = 0.5 / 32.0;
    std::mt19937 rng(51);
    std::uniform_real_distribution<Real> offset(-offsetRange, offsetRange);
    std::vector<Vec<D>> points;
    for (int i = 0; i < POINTS; ++i) {
        const Vec<D> y = shape.surfacePoint(randomUnit<D>(rng));
        points.push_back(y + offset(rng) * shape.normal(y));
    }
    std::vector<LevelErrors> result;
    for (int level : {5, 6, 7}) {
        const auto sampler = makeSampler<D>(makeGrid(level));
        LevelErrors e{level, 0, 0, 0};
        for (const Vec<D>& x : points) {
            RawFields<D> f;
            EXPECT_TRUE(sampler->sample(x, f, nullptr));
            const Vec<D> y = shape.closestPoint(x);
            const Real d = shape.signedDistance(x);
            const Vec<D> n = f.n.normalized();
            const Mat<D> S = f.R * f.R;
            const auto kappa = test::offsetCurvatures<D>(shape.principalCurvatures(y), d);
            const auto lambda = test::tangentialEigenvalues<D>(S, n);
            e.normal = std::max(e.normal, (n - shape.normal(y)).norm());
            e.curvature =
                std::max(e.curvature, (lambda - kappa).cwiseAbs().maxCoeff() / maxCurvature);
            e.normalEigenvalue = std::max(e.normalEigenvalue, std::abs(n.dot(S * n) - 1.0));
        }
        result.push_back(e);
    }
    std::printf("%s: level  |n-n*|      rate  curv.rel.err rate  |n.Sn-1|\n", name);
    for (size_t i = 0; i < result.size(); ++i) {
        const LevelErrors& e = result[i];
        const Real rn = i ? std::log2(result[i - 1].normal / e.normal) : 0.0;
        const Real rk = i ? std::log2(result[i - 1].curvature / e.curvature) : 0.0;
        std::printf("%s: %5d  %.3e  %4.2f  %.3e  %4.2f  %.3e\n", name, e.level, e.normal, rn,
                    e.curvature, rk, e.normalEigenvalue);
    }
    return result;
}

void
expectConvergence(const std::vector<LevelErrors>& e, Real normalBound, Real curvatureBound,
                  Real normalEigenvalueBound)
{
    ASSERT_EQ(e.size(), 3u);
    EXPECT_LT(e[2].normal, normalBound);
    EXPECT_LT(e[2].curvature, curvatureBound);
    EXPECT_LT(e[2].normalEigenvalue, normalEigenvalueBound);
    for (size_t i = 1; i < e.size(); ++i) {
        EXPECT_GE(std::log2(e[i - 1].normal / e[i].normal), 1.5) << "level " << e[i].level;
        EXPECT_GE(std::log2(e[i - 1].curvature / e[i].curvature), 1.0) << "level " << e[i].level;
        // n^T S n = 1 holds at the nodes; between them only up to the interpolation error.
        EXPECT_GE(std::log2(e[i - 1].normalEigenvalue / e[i].normalEigenvalue), 1.5)
            << "level " << e[i].level;
    }
}

TEST(FieldSamplerConvergence, Circle)
{
    const AnalyticSphere<2> circle(Vec<2>(0.503, 0.488), 0.3);
    const auto e = convergence<2>("circle", circle, 1.0 / 0.3, [&](int level) {
        return test::createCircleSdf(level, circle.center(), circle.radius(), 3, 6.0);
    });
    expectConvergence(e, 2e-4, 1e-3, 1e-3);
}

TEST(FieldSamplerConvergence, Ellipse)
{
    const AnalyticEllipsoid<2> ellipse(Vec<2>(0.503, 0.488), Vec<2>(0.32, 0.22));
    const auto e = convergence<2>("ellipse", ellipse, 0.32 / (0.22 * 0.22), [&](int level) {
        return test::createEllipseSdf(level, ellipse.center(), ellipse.semiAxes(), 3, 6.0);
    });
    expectConvergence(e, 1.5e-3, 6e-3, 6e-3);
}

TEST(FieldSamplerConvergence, Sphere)
{
    const AnalyticSphere<3> sphere(Vec<3>(0.503, 0.488, 0.511), 0.3);
    const auto e = convergence<3>("sphere", sphere, 1.0 / 0.3, [&](int level) {
        return test::createSphereSdf(level, sphere.center(), sphere.radius(), 3, 6.0);
    });
    expectConvergence(e, 2e-4, 1e-3, 1.5e-3);
}

TEST(FieldSamplerConvergence, Ellipsoid)
{
    const AnalyticEllipsoid<3> ellipsoid(Vec<3>(0.503, 0.488, 0.511), Vec<3>(0.32, 0.25, 0.2));
    const auto e = convergence<3>("ellipsoid", ellipsoid, 0.32 / (0.2 * 0.2), [&](int level) {
        return test::createEllipsoidSdf(level, ellipsoid.center(), ellipsoid.semiAxes(), 3, 6.0);
    });
    expectConvergence(e, 2e-3, 1e-2, 1.2e-2);
}
