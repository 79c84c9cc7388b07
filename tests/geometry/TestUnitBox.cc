/// @file TestUnitBox.cc
/// @brief Tests of the placement of two shapes in Omega = (0,1)^3 and of the resampling of level
/// sets (narrow band or exact, any voxel size and transform) as signed distances in Omega.

#include <vdbmatch/geometry/ShapeFields.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Diagnostics.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <tbb/global_control.h>

#include <array>
#include <cmath>
#include <string>

using namespace vdbmatch;

namespace {

constexpr double EPS = 1e-9;
/// Largest error of a resampled sphere's distance, in output voxels, over every active voxel.
/// Measured: 0.03-0.11 for the cases below (levels 4, 5), up to 0.25 for assets/sphere.vdb at
/// level 7 (input voxels 1.7 output voxels wide); it is the error of the polygon mesh extracted
/// from the input.
constexpr double MAX_DISTANCE_ERROR_VOXELS = 0.3;

/// A sphere level set in world space with a given transform (a 3-voxel band unless
/// halfWidth says otherwise).
openvdb::FloatGrid::Ptr
worldSphere(const openvdb::Vec3d& centre, double radius, double voxel, double rotation = 0.0,
            const openvdb::Vec3d& translation = openvdb::Vec3d(0.0), float halfWidth = 3.0f)
{
    // Build in index-aligned world space, then attach the rotated transform: with rotation R
    // and translation t, world = R (i v) + t, so the sphere must be made around R^-1 (c - t).
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(voxel);
    xform->postRotate(rotation, openvdb::math::Z_AXIS);
    xform->postTranslate(translation);
    const openvdb::Vec3d local = xform->worldToIndex(centre) * voxel;
    auto grid = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        float(radius), openvdb::Vec3f(local), float(voxel), halfWidth);
    grid->setTransform(xform);
    grid->setName("surface");
    return grid;
}

/// Largest |d - exact| in voxels over the active voxels of a resampled sphere.
double
maxDistanceError(const openvdb::FloatGrid& grid, const openvdb::Vec3d& centreUnit,
                 double radiusUnit)
{
    const double h = grid.voxelSize()[0];
    double worst = 0.0;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        const double exact = (it.getCoord().asVec3d() * h - centreUnit).length() - radiusUnit;
        worst = std::max(worst, std::abs(double(*it) - exact) / h);
    }
    return worst;
}

class UnitBoxTest : public ::testing::Test
{
protected:
    void SetUp() override { openvdb::initialize(); }
};

} // namespace

TEST_F(UnitBoxTest, FromWorldBoxCentresAndScales)
{
    const openvdb::BBoxd box(openvdb::Vec3d(-1.0, 2.0, 3.0), openvdb::Vec3d(3.0, 4.0, 4.0));
    const UnitBoxPlacement p = UnitBoxPlacement::fromWorldBox(box, 0.2);
    EXPECT_NEAR(p.scale, 0.6 / 4.0, EPS);
    EXPECT_TRUE(p.toUnit(box.getCenter()).eq(openvdb::Vec3d(0.5), EPS));
    EXPECT_NEAR(p.toUnit(box.min())[0], 0.2, EPS);
    EXPECT_NEAR(p.toUnit(box.max())[0], 0.8, EPS);
    const openvdb::Vec3d x(0.3, -7.0, 11.0);
    EXPECT_TRUE(p.toWorld(p.toUnit(x)).eq(x, EPS));
    EXPECT_NEAR(p.toWorldLength(p.toUnitLength(2.5)), 2.5, EPS);
    EXPECT_EQ(p.margin, 0.2);
}

TEST_F(UnitBoxTest, FromWorldBoxRejectsBadInput)
{
    const openvdb::BBoxd box(openvdb::Vec3d(0.0), openvdb::Vec3d(1.0));
    for (const double margin : {-0.1, 0.5, 0.7, std::nan("")}) {
        EXPECT_THROW(UnitBoxPlacement::fromWorldBox(box, margin), openvdb::ValueError) << margin;
    }
    EXPECT_THROW(UnitBoxPlacement::fromWorldBox(openvdb::BBoxd()), openvdb::ValueError);
    EXPECT_THROW(
        UnitBoxPlacement::fromWorldBox(openvdb::BBoxd(openvdb::Vec3d(1.0), openvdb::Vec3d(1.0))),
        openvdb::ValueError);
}

TEST_F(UnitBoxTest, ZeroLevelSetBoxContainsTheSurface)
{
    const openvdb::Vec3d c(0.3, -1.2, 2.0);
    const double r = 1.1, voxel = 0.07;
    for (const double rotation : {0.0, 0.5}) {
        const auto grid = worldSphere(c, r, voxel, rotation, openvdb::Vec3d(0.01, 0.02, -0.03));
        const openvdb::BBoxd box = zeroLevelSetWorldBox(*grid);
        for (int a = 0; a < 3; ++a) {
            EXPECT_LE(box.min()[a], c[a] - r) << a;
            EXPECT_GE(box.max()[a], c[a] + r) << a;
            // At most one voxel plus half a voxel diagonal too large.
            EXPECT_GE(box.min()[a], c[a] - r - 2.0 * voxel) << a;
            EXPECT_LE(box.max()[a], c[a] + r + 2.0 * voxel) << a;
        }
    }
}

TEST_F(UnitBoxTest, PlacementPutsBothShapesInsideTheMargin)
{
    const openvdb::Vec3d c1(0.0), c2(1.5, 0.4, -0.3);
    const double r1 = 1.0, r2 = 0.6;
    const auto source = worldSphere(c1, r1, 0.06);
    const auto target = worldSphere(c2, r2, 0.045, 0.3, openvdb::Vec3d(0.1, 0.0, 0.2));
    for (const double margin : {0.0, 0.2, 0.35}) {
        const UnitBoxPlacement p = placeInUnitBox(*source, *target, margin);
        EXPECT_EQ(p.margin, margin);
        double largestSide = 0.0;
        for (const auto* grid : {source.get(), target.get()}) {
            const openvdb::BBoxd box = zeroLevelSetWorldBox(*grid);
            for (int corner = 0; corner < 8; ++corner) {
                const openvdb::Vec3d w(corner & 1 ? box.max()[0] : box.min()[0],
                                       corner & 2 ? box.max()[1] : box.min()[1],
                                       corner & 4 ? box.max()[2] : box.min()[2]);
                const openvdb::Vec3d u = p.toUnit(w);
                for (int a = 0; a < 3; ++a) {
                    EXPECT_GE(u[a], margin - EPS);
                    EXPECT_LE(u[a], 1.0 - margin + EPS);
                }
            }
        }
        // The union box fills 1 - 2 margin along its largest side (x here).
        const openvdb::BBoxd both = [&] {
            openvdb::BBoxd b = zeroLevelSetWorldBox(*source);
            b.expand(zeroLevelSetWorldBox(*target));
            return b;
        }();
        largestSide = p.toUnitLength(both.extents()[0]);
        EXPECT_NEAR(largestSide, 1.0 - 2.0 * margin, EPS);
        // The spheres themselves are inside too.
        for (int a = 0; a < 3; ++a) {
            EXPECT_GE(p.toUnit(c1)[a] - p.toUnitLength(r1), margin - EPS);
            EXPECT_LE(p.toUnit(c2)[a] + p.toUnitLength(r2), 1.0 - margin + EPS);
        }
    }
}

/// Input variants: narrow band (Houdini-like), wide (exact) band, rotated and translated
/// transform with another voxel size.
struct ResampleCase
{
    const char* name;
    double voxel;
    double rotation;
    openvdb::Vec3d translation;
    float halfWidth;
};

class ResampleTest : public UnitBoxTest, public ::testing::WithParamInterface<ResampleCase>
{
};

TEST_P(ResampleTest, SphereDistancesAreAccurateEverywhereInTheBox)
{
    const ResampleCase& rc = GetParam();
    const openvdb::Vec3d c(0.4, -0.2, 0.1);
    const double r = 1.0;
    const auto input = worldSphere(c, r, rc.voxel, rc.rotation, rc.translation, rc.halfWidth);
    // Place with a larger box so that the sphere is off-centre in Omega.
    const openvdb::BBoxd box(c - openvdb::Vec3d(r), c + openvdb::Vec3d(2.0 * r));
    const UnitBoxPlacement p = UnitBoxPlacement::fromWorldBox(box, 0.2);
    for (const int level : {4, 5}) {
        const auto grid = resampleToUnitBox(*input, p, level);
        ASSERT_TRUE(grid);
        const double h = std::ldexp(1.0, -level);
        EXPECT_EQ(grid->getName(), "surface");
        EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
        EXPECT_TRUE(grid->transform().isLinear());
        EXPECT_TRUE(grid->indexToWorld(openvdb::Coord(1, 2, 3)).eq(openvdb::Vec3d(1, 2, 3) * h));
        EXPECT_TRUE(grid->indexToWorld(openvdb::Coord(0)).eq(openvdb::Vec3d(0.0)));
        EXPECT_TRUE(coversUnitBoxNodes(*grid, level));
        EXPECT_EQ(openvdb::tools::checkLevelSet(*grid, 8), "");
        EXPECT_DOUBLE_EQ(validateDistanceGrid(*grid, "test"), h);
        for (auto it = grid->cbeginValueAll(); it; ++it)
            ASSERT_TRUE(std::isfinite(*it));
        const openvdb::Vec3d cu = p.toUnit(c);
        const double ru = p.toUnitLength(r);
        EXPECT_LT(maxDistanceError(*grid, cu, ru), MAX_DISTANCE_ERROR_VOXELS) << level;
        // Sign: negative inside, positive outside, also far from the band.
        const openvdb::Coord centreNode = openvdb::Coord::round(cu / h);
        EXPECT_LT(grid->tree().getValue(centreNode), -0.5 * ru);
        EXPECT_GT(grid->tree().getValue(openvdb::Coord((1 << level) + UNIT_BOX_NODE_PADDING)), 0.5);
    }
}

INSTANTIATE_TEST_SUITE_P(
    Inputs, ResampleTest,
    ::testing::Values(ResampleCase{"NarrowBand", 0.05, 0.0, openvdb::Vec3d(0.0), 3.0f},
                      ResampleCase{"ExactWideBand", 0.05, 0.0, openvdb::Vec3d(0.0), 30.0f},
                      ResampleCase{"RotatedTranslated", 0.037, 0.7,
                                   openvdb::Vec3d(0.013, -0.2, 5.0), 3.0f},
                      ResampleCase{"CoarseInput", 0.15, 0.2, openvdb::Vec3d(0.0), 3.0f}),
    [](const ::testing::TestParamInfo<ResampleCase>& testInfo) { return testInfo.param.name; });

TEST_F(UnitBoxTest, WideBandIsValidOutsideTheBoxToo)
{
    const auto input = worldSphere(openvdb::Vec3d(0.0), 1.0, 0.05);
    const UnitBoxPlacement p = UnitBoxPlacement::fromWorldBox(
        openvdb::BBoxd(openvdb::Vec3d(-1.0), openvdb::Vec3d(1.0)), 0.3);
    const int level = 4;
    const double band = 12.0, h = std::ldexp(1.0, -level);
    const auto grid = resampleToUnitBox(*input, p, level, band);
    // A node outside the node box but within the band: x = 0.5 + 0.2 + 0.3 + 10 h along +x.
    const openvdb::Coord outside(int(std::lround((1.0 + 0.3) / h)), 8, 8);
    ASSERT_TRUE(grid->tree().isValueOn(outside));
    const double exact = (outside.asVec3d() * h - openvdb::Vec3d(0.5)).length() - 0.2;
    EXPECT_NEAR(grid->tree().getValue(outside), exact, MAX_DISTANCE_ERROR_VOXELS * h);
    EXPECT_GE(grid->background(), float(band * h));
}

TEST_F(UnitBoxTest, ResultsDoNotDependOnTheThreadCount)
{
    const auto input = worldSphere(openvdb::Vec3d(0.1, 0.0, 0.0), 1.0, 0.05, 0.3);
    const UnitBoxPlacement p = placeInUnitBox(*input, *input);
    const auto threaded = resampleToUnitBox(*input, p, 5);
    openvdb::FloatGrid::Ptr serial;
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        serial = resampleToUnitBox(*input, p, 5);
    }
    ASSERT_EQ(serial->activeVoxelCount(), threaded->activeVoxelCount());
    const auto acc = threaded->getConstAccessor();
    for (auto it = serial->cbeginValueOn(); it; ++it) {
        ASSERT_TRUE(acc.isValueOn(it.getCoord()));
        ASSERT_EQ(*it, acc.getValue(it.getCoord())) << it.getCoord();
    }
}

TEST_F(UnitBoxTest, ResampleRejectsBadArguments)
{
    const auto input = worldSphere(openvdb::Vec3d(0.0), 1.0, 0.1);
    const UnitBoxPlacement p = placeInUnitBox(*input, *input);
    EXPECT_THROW(resampleToUnitBox(*input, p, 0), openvdb::ValueError);
    EXPECT_THROW(resampleToUnitBox(*input, p, 13), openvdb::ValueError);
    EXPECT_THROW(resampleToUnitBox(*input, p, 4, 2.0), openvdb::ValueError);
    UnitBoxPlacement bad = p;
    bad.scale = 0.0;
    EXPECT_THROW(resampleToUnitBox(*input, bad, 4), openvdb::ValueError);
    // A placement that puts the surface far outside Omega.
    UnitBoxPlacement away = p;
    away.worldOrigin = openvdb::Vec3d(-100.0);
    EXPECT_THROW(resampleToUnitBox(*input, away, 4), openvdb::ValueError);
}
