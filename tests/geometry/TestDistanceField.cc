/// @file TestDistanceField.cc
/// @brief Tests of the distance grids of explicit surfaces on Omega nodes (accuracy against
/// analytic sphere / circle distances, signs everywhere in the box, level set validity), of the
/// tiered shape sampler (coverage of the whole box, finest tier near the surface) and of
/// levelSetFromSurface.

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/DistanceField.h>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Diagnostics.h>

#include <cmath>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

const Vec<3> CENTRE3(0.5, 0.5, 0.5);
const Vec<2> CENTRE2(0.5, 0.5);
constexpr double RADIUS = 0.3;
/// Largest error of the 3D band against the analytic sphere, voxels: the distance to the
/// triangles is exact, the error is the chordal error of the mesh (3.6e-4, i.e. 0.023 voxel at
/// level 6, measured 0.011).
constexpr double MAX_BAND_ERROR_3D = 0.03;

/// A fine UV sphere: its chordal error (< 1e-4) is far below the voxels used here.
Surface<3>
sphere()
{
    return uvSphere(CENTRE3, RADIUS, 64, 128);
}

/// A regular 1024-gon: chordal error 1.4e-6.
Surface<2>
circle2()
{
    return circle(CENTRE2, RADIUS, 1024);
}

template <int D>
Vec<D>
nodePosition(const openvdb::Coord& c, double h)
{
    Vec<D> x;
    for (int a = 0; a < D; ++a)
        x[a] = c[a] * h;
    return x;
}

/// Largest |d - exact| / h over the active nodes, and the count of active nodes.
template <int D>
double
maxActiveError(const openvdb::FloatGrid& grid, const Vec<D>& centre, double h, size_t& count)
{
    double worst = 0.0;
    count = 0;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const double exact = (nodePosition<D>(it.getCoord(), h) - centre).norm() - RADIUS;
        worst = std::max(worst, std::abs(double(*it) - exact) / h);
        ++count;
    }
    return worst;
}

class DistanceFieldTest : public ::testing::Test
{
protected:
    void SetUp() override { openvdb::initialize(); }
};

} // namespace

TEST_F(DistanceFieldTest, Band3DIsAccurate)
{
    const int level = 6;
    const double h = std::ldexp(1.0, -level), hw = 4.0;
    const auto grid = distanceBand<3>(sphere(), level, hw);
    EXPECT_EQ(openvdb::tools::checkLevelSet(*grid, 8), "");
    EXPECT_EQ(grid->getName(), "surface");
    EXPECT_NEAR(grid->background(), hw * h, 1e-7);
    EXPECT_TRUE(grid->transform()
                    .indexToWorld(openvdb::Vec3d(1, 2, 3))
                    .eq(openvdb::Vec3d(h, 2 * h, 3 * h)));
    size_t count = 0;
    EXPECT_LT(maxActiveError<3>(*grid, CENTRE3, h, count), MAX_BAND_ERROR_3D);
    // Every node with |exact| <= (hw - 0.5) h is active.
    const auto acc = grid->getConstAccessor();
    for (int i = 0; i <= 64; i += 1) {
        const openvdb::Coord c(i, 32, 32);
        const double exact = (nodePosition<3>(c, h) - CENTRE3).norm() - RADIUS;
        if (std::abs(exact) <= (hw - 0.5) * h) {
            EXPECT_TRUE(acc.isValueOn(c)) << i;
        }
        // Signs of inactive values too.
        EXPECT_EQ(acc.getValue(c) < 0.0f, exact < 0.0) << i;
    }
}

TEST_F(DistanceFieldTest, Band2DIsExact)
{
    const int level = 8;
    const double h = std::ldexp(1.0, -level), hw = 5.0;
    // Orientation must not matter: both orientations give the same grid.
    Surface<2> cw;
    addCircle(cw, CENTRE2, RADIUS, 1024, /*clockwise=*/true);
    for (const Surface<2>& s : {circle2(), cw}) {
        const auto grid = distanceBand<2>(s, level, hw);
        EXPECT_EQ(openvdb::tools::checkLevelSet(*grid, 8), "");
        size_t count = 0;
        EXPECT_LT(maxActiveError<2>(*grid, CENTRE2, h, count), 1e-3);
        // All band nodes of the slice are active; nothing off the slice.
        const size_t expected = size_t(std::round(2.0 * M_PI * RADIUS / h * 2.0 * hw));
        EXPECT_NEAR(double(count), double(expected), 0.02 * double(expected));
        EXPECT_EQ(grid->evalActiveVoxelBoundingBox().max()[2], 0);
        EXPECT_EQ(grid->evalActiveVoxelBoundingBox().min()[2], 0);
        // Inactive signs: far inside and far outside.
        EXPECT_LT(grid->tree().getValue(openvdb::Coord(128, 128, 0)), 0.0f);
        EXPECT_GT(grid->tree().getValue(openvdb::Coord(2, 2, 0)), 0.0f);
    }
}

TEST_F(DistanceFieldTest, Box2DHasExactDistancesAndSignsEverywhere)
{
    // A circle with a hole (an annulus) and a vertex exactly on a node row.
    Surface<2> s = circle2();
    addCircle(s, CENTRE2, 0.1, 4); // square hole with vertices at rows y = 0.5
    const int level = 5, padding = 3;
    const double h = std::ldexp(1.0, -level);
    const auto grid = distanceBox<2>(s, level, padding);
    EXPECT_EQ(openvdb::tools::checkLevelSet(*grid, 8), "");
    const auto acc = grid->getConstAccessor();
    const int n = 1 << level;
    double worst = 0.0;
    for (int j = -padding; j <= n + padding; ++j) {
        for (int i = -padding; i <= n + padding; ++i) {
            const openvdb::Coord c(i, j, 0);
            ASSERT_TRUE(acc.isValueOn(c)) << c;
            const Vec<2> x = nodePosition<2>(c, h);
            // Distance to the annulus of the polygons: the outer circle, the inner square.
            double dSquare = 1e9;
            for (int k = 0; k < 4; ++k) {
                const size_t a = 1024 + size_t(k), b = 1024 + size_t((k + 1) % 4);
                const Vec<2> p = s.points[a], q = s.points[b];
                const double t = std::clamp((x - p).dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
                dSquare = std::min(dSquare, (x - p - t * (q - p)).norm());
            }
            const double rho = (x - CENTRE2).norm();
            const bool insideSquare = std::abs(x[0] - 0.5) + std::abs(x[1] - 0.5) < 0.1;
            const double dCircle = std::abs(rho - RADIUS);
            const bool inside = rho < RADIUS && !insideSquare;
            const double exact = (inside ? -1.0 : 1.0) * std::min(dCircle, dSquare);
            worst = std::max(worst, std::abs(double(acc.getValue(c)) - exact));
        }
    }
    EXPECT_LT(worst, 1e-3 * h);
}

TEST_F(DistanceFieldTest, Box3DCoversTheBoxWithCorrectSigns)
{
    const int level = 4, padding = 3;
    const double h = std::ldexp(1.0, -level);
    const auto grid = distanceBox<3>(sphere(), level, padding);
    EXPECT_EQ(openvdb::tools::checkLevelSet(*grid, 8), "");
    EXPECT_TRUE(coversUnitBoxNodes(*grid, level, padding));
    const auto acc = grid->getConstAccessor();
    const int n = 1 << level;
    double worst = 0.0;
    for (int k = -padding; k <= n + padding; ++k)
        for (int j = -padding; j <= n + padding; ++j)
            for (int i = -padding; i <= n + padding; ++i) {
                const openvdb::Coord c(i, j, k);
                const double exact = (nodePosition<3>(c, h) - CENTRE3).norm() - RADIUS;
                const double d = acc.getValue(c);
                if (std::abs(exact) > 1e-3) {
                    EXPECT_EQ(d < 0.0, exact < 0.0) << c;
                }
                worst = std::max(worst, std::abs(d - exact) / h);
            }
    EXPECT_LT(worst, MAX_BAND_ERROR_3D);
}

TEST_F(DistanceFieldTest, SamplerCoversTheBoxIn3D)
{
    const int level = 6;
    ShapeSamplerOptions opts;
    opts.denseLevel3D = 3; // three tiers: bands at 6 and 4, box at 3
    const auto sampler = buildShapeSampler<3>(sphere(), level, opts);
    ASSERT_EQ(sampler->tierCount(), 3u);
    EXPECT_DOUBLE_EQ(sampler->voxelSize(0), std::ldexp(1.0, -6));
    EXPECT_DOUBLE_EQ(sampler->voxelSize(1), std::ldexp(1.0, -4));
    EXPECT_DOUBLE_EQ(sampler->voxelSize(2), std::ldexp(1.0, -3));
    const double hc = std::ldexp(1.0, -3), lo = -2.0 * hc, hi = 1.0 + 2.0 * hc;
    const int samples = 23;
    for (int k = 0; k < samples; ++k)
        for (int j = 0; j < samples; ++j)
            for (int i = 0; i < samples; ++i) {
                const Vec<3> x = Vec<3>(lo, lo, lo) + (hi - lo) / (samples - 1) * Vec<3>(i, j, k);
                Real d = 0;
                ASSERT_TRUE(sampler->sampleDistance(x, d)) << x.transpose();
                const double exact = (x - CENTRE3).norm() - RADIUS;
                // The coarsest tier's quasi-interpolation error is O(hc^2 curvature), except
                // at the medial axis (the centre), where d has a kink.
                if ((x - CENTRE3).norm() > 2.0 * hc) {
                    EXPECT_NEAR(d, exact, 0.25 * hc) << x.transpose();
                }
                if (std::abs(exact) > 0.5 * hc) {
                    EXPECT_EQ(d < 0.0, exact < 0.0);
                }
            }
    // Near the surface the finest tier is used, and it is accurate.
    for (int k = 0; k < 50; ++k) {
        const double t = 0.7 * k, s = 1.3 * k;
        const Vec<3> dir(std::sin(t) * std::cos(s), std::sin(t) * std::sin(s), std::cos(t));
        const Vec<3> x = CENTRE3 + (RADIUS + 0.02 * std::sin(3.0 * k)) * dir;
        EXPECT_EQ(sampler->findTier(x), 0);
        Real d = 0;
        ASSERT_TRUE(sampler->sampleDistance(x, d));
        EXPECT_NEAR(d, (x - CENTRE3).norm() - RADIUS, 0.1 * std::ldexp(1.0, -6));
    }
}

TEST_F(DistanceFieldTest, SamplerCoversTheBoxIn2D)
{
    for (const int dense : {7, 5}) {
        const int level = 9;
        ShapeSamplerOptions opts;
        opts.denseLevel2D = dense;
        const auto sampler = buildShapeSampler<2>(circle2(), level, opts);
        EXPECT_EQ(sampler->tierCount(), dense == 7 ? 2u : 3u);
        const double hc = std::ldexp(1.0, -dense), lo = -2.0 * hc, hi = 1.0 + 2.0 * hc;
        const int samples = 101;
        for (int j = 0; j < samples; ++j)
            for (int i = 0; i < samples; ++i) {
                const Vec<2> x = Vec<2>(lo, lo) + (hi - lo) / (samples - 1) * Vec<2>(i, j);
                Real d = 0;
                ASSERT_TRUE(sampler->sampleDistance(x, d)) << x.transpose();
                const double exact = (x - CENTRE2).norm() - RADIUS;
                if ((x - CENTRE2).norm() > 2.0 * hc) {
                    EXPECT_NEAR(d, exact, 0.25 * hc) << x.transpose();
                }
                if (std::abs(exact) > 0.5 * hc) {
                    EXPECT_EQ(d < 0.0, exact < 0.0);
                }
            }
        const Vec<2> near = CENTRE2 + Vec<2>(RADIUS + 0.003, 0.001);
        EXPECT_EQ(sampler->findTier(near), 0);
    }
}

TEST_F(DistanceFieldTest, SamplerCacheGivesTheSameSamplerAtEveryLevel)
{
    // Levels 3..7 with the dense level 3 in 2D: the box tier at 3 serves every level, the band
    // at l - 2 is the finest tier of level l - 2. Each cached sampler must equal a fresh one bit
    // for bit.
    ShapeSamplerOptions opts;
    opts.denseLevel2D = 3;
    const Surface<2> shape = circle2();
    ShapeSamplerCache<2> cache;
    for (int level = 3; level <= 7; ++level) {
        const auto cached = buildShapeSampler<2>(shape, level, opts, cache);
        const auto fresh = buildShapeSampler<2>(shape, level, opts);
        ASSERT_EQ(cached->tierCount(), fresh->tierCount()) << level;
        for (size_t t = 0; t < fresh->tierCount(); ++t) {
            EXPECT_EQ(cached->voxelSize(t), fresh->voxelSize(t));
            EXPECT_EQ(cached->blockCount(t), fresh->blockCount(t));
        }
        for (int j = 0; j < 67; ++j)
            for (int i = 0; i < 67; ++i) {
                const Vec<2> x = Vec<2>(-0.05, -0.05) + (1.1 / 66) * Vec<2>(i, j);
                RawFields<2> a{}, b{};
                RawFieldDerivatives<2> da{}, db{};
                ASSERT_TRUE(cached->sample(x, a, &da)) << x.transpose();
                ASSERT_TRUE(fresh->sample(x, b, &db));
                EXPECT_EQ(a.d, b.d);
                EXPECT_EQ(a.n, b.n);
                EXPECT_EQ(a.R, b.R);
                EXPECT_EQ(da.dd, db.dd);
            }
    }
    // Used with another surface, the cache refuses instead of mixing shapes.
    const Surface<2> other = circle(CENTRE2, 0.2, 256);
    EXPECT_THROW(buildShapeSampler<2>(other, 5, opts, cache), openvdb::ValueError);
}

TEST_F(DistanceFieldTest, LevelSetFromSurface)
{
    // 3D: a sphere of radius 3 around (1, 2, 3) in a transform with voxel 0.25 and an offset.
    auto xform = openvdb::math::Transform::createLinearTransform(0.25);
    xform->postTranslate(openvdb::Vec3d(0.1, -0.05, 0.3));
    const Surface<3> s3 = uvSphere(Vec<3>(1, 2, 3), 3.0, 64, 128);
    const auto grid3 = levelSetFromSurface<3>(s3, *xform);
    EXPECT_EQ(openvdb::tools::checkLevelSet(*grid3, 8), "");
    EXPECT_EQ(grid3->getName(), "surface");
    EXPECT_NEAR(grid3->background(), 3.0 * 0.25, 1e-6);
    double worst = 0.0;
    for (auto it = grid3->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d w = xform->indexToWorld(it.getCoord());
        const double exact = (Vec<3>(w[0], w[1], w[2]) - Vec<3>(1, 2, 3)).norm() - 3.0;
        worst = std::max(worst, std::abs(*it - exact));
    }
    EXPECT_LT(worst, 3.0 * (1.0 - std::cos(M_PI / 64.0))); // the mesh's chordal error

    // 2D: a circle in a slice with voxel 0.01 and an offset.
    auto xform2 = openvdb::math::Transform::createLinearTransform(0.01);
    xform2->postTranslate(openvdb::Vec3d(0.003, -0.002, 0.0));
    const Surface<2> s2 = circle(Vec<2>(-1.0, 2.0), 0.5, 2048);
    const auto grid2 = levelSetFromSurface<2>(s2, *xform2, 4.0);
    EXPECT_EQ(openvdb::tools::checkLevelSet(*grid2, 8), "");
    EXPECT_EQ(grid2->evalActiveVoxelBoundingBox().max()[2], 0);
    worst = 0.0;
    for (auto it = grid2->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d w = xform2->indexToWorld(it.getCoord());
        worst = std::max(worst,
                         std::abs(*it - ((Vec<2>(w[0], w[1]) - Vec<2>(-1.0, 2.0)).norm() - 0.5)));
    }
    EXPECT_LT(worst, 1e-4);
    auto rotated = openvdb::math::Transform::createLinearTransform(0.01);
    rotated->postRotate(0.3, openvdb::math::Z_AXIS);
    EXPECT_THROW(levelSetFromSurface<2>(s2, *rotated), openvdb::ValueError);
}

TEST_F(DistanceFieldTest, RejectsInvalidArguments)
{
    EXPECT_THROW(distanceBand<2>(circle2(), 0, 4.0), openvdb::ValueError);
    EXPECT_THROW(distanceBand<2>(circle2(), 5, 2.0), openvdb::ValueError);
    EXPECT_THROW(distanceBox<3>(sphere(), 13), openvdb::ValueError);
    Surface<2> open = circle2();
    open.elements.pop_back();
    EXPECT_THROW(distanceBand<2>(open, 5, 4.0), openvdb::ValueError);
}
