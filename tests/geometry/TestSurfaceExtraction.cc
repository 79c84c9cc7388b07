/// @file TestSurfaceExtraction.cc
/// @brief Tests of extractSurface (a closed mesh near a sphere from a 3-voxel band) and of
/// isSlice / extractCurve (length, area and orientation of a circle, saddle cells).

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/SurfaceExtraction.h>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

/// A slice level set (layer k) of the circle of radius r around c (world units), with a band of
/// @a halfWidth voxels, voxel size h and a translation.
openvdb::FloatGrid::Ptr
circleSlice(const Vec<2>& c, double r, double h, int k, double halfWidth,
            const openvdb::Vec3d& translation = openvdb::Vec3d(0.0))
{
    auto grid = openvdb::FloatGrid::create(float(halfWidth * h));
    auto xform = openvdb::math::Transform::createLinearTransform(h);
    xform->postTranslate(translation);
    grid->setTransform(xform);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("curve");
    auto acc = grid->getAccessor();
    const openvdb::Vec3d lo = xform->worldToIndex(openvdb::Vec3d(c[0] - r, c[1] - r, 0.0));
    const openvdb::Vec3d hi = xform->worldToIndex(openvdb::Vec3d(c[0] + r, c[1] + r, 0.0));
    const int pad = int(halfWidth) + 2;
    for (int j = int(lo[1]) - pad; j <= int(hi[1]) + pad; ++j) {
        for (int i = int(lo[0]) - pad; i <= int(hi[0]) + pad; ++i) {
            const openvdb::Vec3d w = xform->indexToWorld(openvdb::Vec3d(i, j, k));
            const double d = (Vec<2>(w[0], w[1]) - c).norm() - r;
            if (std::abs(d) <= halfWidth * h)
                acc.setValueOn(openvdb::Coord(i, j, k), float(d));
            else
                acc.setValueOff(openvdb::Coord(i, j, k),
                                d < 0 ? -float(halfWidth * h) : float(halfWidth * h));
        }
    }
    return grid;
}

/// A slice k = 0 with value +1 (active) on [-1, 4]^2 except the given nodes.
openvdb::FloatGrid::Ptr
saddleSlice(float inside0, float inside1, float outsideDiagonal)
{
    auto grid = openvdb::FloatGrid::create(3.0f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    auto acc = grid->getAccessor();
    for (int j = -1; j <= 4; ++j)
        for (int i = -1; i <= 4; ++i)
            acc.setValueOn(openvdb::Coord(i, j, 0), 1.0f);
    // Cell (1,1)-(2,2): inside corners (1,1) and (2,2), outside (2,1) and (1,2).
    acc.setValueOn(openvdb::Coord(1, 1, 0), inside0);
    acc.setValueOn(openvdb::Coord(2, 2, 0), inside1);
    acc.setValueOn(openvdb::Coord(2, 1, 0), outsideDiagonal);
    acc.setValueOn(openvdb::Coord(1, 2, 0), outsideDiagonal);
    return grid;
}

} // namespace

TEST(SurfaceExtraction, SphereFromAThinBandIsClosedAndAccurate)
{
    openvdb::initialize();
    const double r = 1.0, h = 0.05;
    const openvdb::Vec3f c(0.3f, -0.2f, 0.1f);
    auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(r), c, float(h),
                                                                         /*halfWidth=*/3.0f);
    const Surface<3> s = extractSurface(*grid);
    EXPECT_NO_THROW(checkSurface(s, "sphere"));
    double worst = 0.0;
    for (const auto& p : s.points)
        worst = std::max(worst, std::abs((p - Vec<3>(c[0], c[1], c[2])).norm() - r));
    // Measured: 0.0025 h.
    EXPECT_LT(worst, 0.02 * h);
    EXPECT_NEAR(measure(s), 4.0 * M_PI * r * r, 0.005 * 4.0 * M_PI * r * r);
    EXPECT_NEAR(std::abs(signedVolume(s)), 4.0 / 3.0 * M_PI * r * r * r, 0.005 * 4.2);
    EXPECT_FALSE(isSlice(*grid));
    EXPECT_THROW(extractCurve(*grid), openvdb::ValueError);
    EXPECT_THROW(extractSurface(*openvdb::FloatGrid::create(3.0f)), openvdb::ValueError);
}

TEST(SurfaceExtraction, CircleSliceHasTheRightLengthAndArea)
{
    const Vec<2> c(0.4, -0.3);
    const double r = 0.7, h = 0.02;
    for (const int k : {0, 5}) {
        // Houdini-style 3-voxel band, translated transform, any layer k.
        const auto grid = circleSlice(c, r, h, k, 3.0, openvdb::Vec3d(0.013, -0.007, 2.0));
        ASSERT_TRUE(isSlice(*grid));
        const Surface<2> s = extractCurve(*grid);
        EXPECT_NO_THROW(checkSurface(s, "circle"));
        EXPECT_EQ(countLoops(s), 1);
        // The inscribed polygon: relative errors O((h/r)^2).
        EXPECT_NEAR(measure(s), 2.0 * M_PI * r, 1e-3 * 2.0 * M_PI * r);
        // Counter-clockwise around the inside.
        EXPECT_NEAR(signedVolume(s), M_PI * r * r, 1e-3 * M_PI * r * r);
        double worst = 0.0;
        for (const auto& p : s.points)
            worst = std::max(worst, std::abs((p - c).norm() - r));
        EXPECT_LT(worst, 0.01 * h); // linear interpolation of an exact distance
    }
}

TEST(SurfaceExtraction, SaddleCellsAreResolvedByTheAsymptoticDecider)
{
    // Saddle value (ac - bd) / (a + c - b - d) = 0 with a = c = -1, b = d = 1: separate.
    const Surface<2> separate = extractCurve(*saddleSlice(-1.0f, -1.0f, 1.0f));
    EXPECT_NO_THROW(checkSurface(separate, "separate"));
    EXPECT_EQ(countLoops(separate), 2);
    EXPECT_EQ(separate.elements.size(), 8u);
    EXPECT_GT(signedVolume(separate), 0.0);
    // With b = d = 0.5 the saddle value is -0.25: the inside corners are joined.
    const Surface<2> joined = extractCurve(*saddleSlice(-1.0f, -1.0f, 0.5f));
    EXPECT_NO_THROW(checkSurface(joined, "joined"));
    EXPECT_EQ(countLoops(joined), 1);
    EXPECT_GT(signedVolume(joined), 0.0);
    // Deterministic: the same grid gives the same curve.
    const Surface<2> again = extractCurve(*saddleSlice(-1.0f, -1.0f, 0.5f));
    EXPECT_EQ(again.points, joined.points);
    EXPECT_EQ(again.elements, joined.elements);
}
