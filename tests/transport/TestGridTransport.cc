/// @file TestGridTransport.cc
/// @brief Tests of transportGrid: a level set sphere moved by an affine map is the moved sphere's
/// distance; a linear field is carried exactly (g = f o phi^-1, trilinear sampling is exact on
/// linear functions); forward then inverse restores a level set; 2D slices; unsupported types;
/// thread independence.

#include "support/SwirlGrid.h"

#include <vdbmatch/geometry/SurfaceExtraction.h>
#include <vdbmatch/transport/GridTransport.h>

#include <gtest/gtest.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <cstdio>

using namespace vdbmatch;
using namespace vdbmatch::test;
using openvdb::Mat3d;
using openvdb::Vec3d;

namespace {

constexpr double VOXEL = 0.125; // deformation domain [0, 4]^3 at level 5

Mat3d
stretch()
{
    return Mat3d(1.15, 0.1, 0.0,  //
                 0.0, 0.95, 0.05, //
                 0.0, 0.0, 1.05);
}

/// A fog block with the linear values f(x) = 1 + a . x on [lo, hi]^3 (index box), transform of
/// voxel @a voxel.
openvdb::FloatGrid::Ptr
linearFog(double voxel, int lo, int hi, const Vec3d& a)
{
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    grid->setName("density");
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    auto acc = grid->getAccessor();
    for (int k = lo; k <= hi; ++k)
        for (int j = lo; j <= hi; ++j)
            for (int i = lo; i <= hi; ++i) {
                const Vec3d x = grid->indexToWorld(openvdb::Coord(i, j, k));
                acc.setValueOn(openvdb::Coord(i, j, k), float(1.0 + a.dot(x)));
            }
    grid->insertMeta("units", openvdb::StringMetadata("kg/m3"));
    return grid;
}

} // namespace

TEST(GridTransport, LevelSetSphereMovesWithAnAffineMap)
{
    // phi = translation by b inside the domain (A = I): the sphere's distance moves by b.
    const Vec3d b(0.3, -0.2, 0.15);
    const DeformationField phi(affineGrid(3, 5, Mat3d::identity(), b, VOXEL));
    const Vec3d centre = phi.worldBounds().getCenter();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.8f, centre, 0.05f);
    sphere->setName("ball");
    sphere->insertMeta("artist", openvdb::StringMetadata("test"));
    const GridTransportResult r = transportGrid(*sphere, phi, false);
    ASSERT_TRUE(r.grid);
    EXPECT_TRUE(r.levelSet);
    EXPECT_EQ(r.inverseFailures, 0u);
    auto out = openvdb::gridPtrCast<openvdb::FloatGrid>(r.grid);
    ASSERT_TRUE(out);
    EXPECT_EQ(out->getName(), "ball");
    EXPECT_EQ(out->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(out->metaValue<std::string>("artist"), "test");
    EXPECT_EQ(out->transform(), sphere->transform());
    EXPECT_NEAR(out->background(), sphere->background(), 1e-6);
    // Distances near the moved surface: |y - (c + b)| - r, up to the surface's facets.
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sample(*out);
    for (const Vec3d dir : {Vec3d(1, 0, 0), Vec3d(0, -1, 0), Vec3d(0.6, 0.0, 0.8)}) {
        for (double offset : {-0.05, 0.0, 0.05}) {
            const Vec3d y = centre + b + dir * (0.8 + offset);
            EXPECT_NEAR(sample.wsSample(y), offset, 0.01) << dir << " " << offset;
        }
    }
}

TEST(GridTransport, LinearFieldIsCarriedExactly)
{
    const Mat3d A = stretch();
    const Vec3d b(0.1, 0.05, -0.1);
    const DeformationField phi(affineGrid(3, 5, A, b, VOXEL));
    const Vec3d c = phi.worldBounds().getCenter();
    const Vec3d a(0.4, -0.3, 0.2);
    // The fog covers the middle of the domain (world [1, 3]^3 with voxel 0.1).
    auto fog = linearFog(0.1, 10, 30, a);
    const Mat3d Ainv = A.inverse();
    for (bool inverse : {false, true}) {
        const GridTransportResult r = transportGrid(*fog, phi, inverse);
        ASSERT_TRUE(r.grid);
        EXPECT_FALSE(r.levelSet);
        auto out = openvdb::gridPtrCast<openvdb::FloatGrid>(r.grid);
        ASSERT_TRUE(out);
        EXPECT_EQ(out->getName(), "density");
        EXPECT_EQ(out->getGridClass(), openvdb::GRID_FOG_VOLUME);
        EXPECT_EQ(out->metaValue<std::string>("units"), "kg/m3");
        std::size_t interior = 0;
        for (auto v = out->cbeginValueOn(); v; ++v) {
            const Vec3d y = out->indexToWorld(v.getCoord());
            // The preimage of y (forward: phi^-1(y); inverse: phi(y)) ...
            const Vec3d x = inverse ? c + A * (y - c) + b : c + Ainv * (y - b - c);
            const Vec3d p = fog->worldToIndex(x);
            // ... well inside the block: the value is f there, exactly.
            if (p.x() < 11 || p.y() < 11 || p.z() < 11 || p.x() > 29 || p.y() > 29 || p.z() > 29)
                continue;
            ++interior;
            EXPECT_NEAR(*v, 1.0 + a.dot(x), 2e-5) << y;
        }
        EXPECT_GT(interior, 5000u);
        // The active region is the image of the block: about det A times its volume.
        const double ratio = double(out->activeVoxelCount()) / double(fog->activeVoxelCount());
        const double expected = inverse ? 1.0 / A.det() : A.det();
        EXPECT_NEAR(ratio, expected, 0.2 * expected);
    }
}

TEST(GridTransport, LevelSetForwardThenInverseIsTheIdentity)
{
    const DeformationField phi(swirlGrid(3, 5, 1.2, VOXEL));
    const Vec3d centre = phi.worldBounds().getCenter();
    // An off-centre box-ish shape so that the swirl really moves it.
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        0.7f, centre + Vec3d(0.6, 0.0, 0.0), 0.05f);
    const GridTransportResult forward = transportGrid(*sphere, phi, false);
    const GridTransportResult back = transportGrid(*forward.grid, phi, true);
    auto moved = openvdb::gridPtrCast<openvdb::FloatGrid>(forward.grid);
    auto restored = openvdb::gridPtrCast<openvdb::FloatGrid>(back.grid);
    ASSERT_TRUE(moved && restored);
    openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> m(*moved),
        s(*restored);
    // phi of the sphere's points lie on the moved surface, and the round trip restores the
    // sphere, within a fraction of a voxel (extractions and rebuilds in between).
    double worstRestored = 0;
    for (int k = 0; k < 64; ++k) {
        const double t = 2 * M_PI * k / 64, z = std::cos(3.0 * t) * 0.5;
        const Vec3d dir(std::cos(t) * std::sqrt(1 - z * z), std::sin(t) * std::sqrt(1 - z * z), z);
        const Vec3d x = centre + Vec3d(0.6, 0.0, 0.0) + 0.7 * dir;
        worstRestored = std::max(worstRestored, double(std::abs(s.wsSample(x))));
        EXPECT_LT(std::abs(m.wsSample(phi.apply(x))), 0.02) << x; // phi(S) is the new surface
    }
    EXPECT_LT(worstRestored, 0.02);
}

TEST(GridTransport, SliceMovesInItsPlane)
{
    // A 2D swirl; a disc slice at layer k = 3 (world z = 0.3) rebuilt in the same plane.
    const DeformationField phi(swirlGrid(2, 6, 1.0, 0.0625));
    const Vec3d centre = phi.worldBounds().getCenter();
    auto grid = openvdb::FloatGrid::create(0.3f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(0.1));
    grid->setName("disc");
    auto acc = grid->getAccessor();
    const Vec3d discCentre = centre + Vec3d(0.8, 0.0, 0.0);
    for (int j = -60; j <= 60; ++j)
        for (int i = -80; i <= 80; ++i) {
            const Vec3d x = grid->indexToWorld(openvdb::Coord(i, j, 3));
            const double d = Vec3d(x[0] - discCentre[0], x[1] - discCentre[1], 0).length() - 0.6;
            if (std::abs(d) < 0.3)
                acc.setValueOn(openvdb::Coord(i, j, 3), float(d));
            else
                acc.setValueOff(openvdb::Coord(i, j, 3), d < 0 ? -0.3f : 0.3f);
        }
    const GridTransportResult r = transportGrid(*grid, phi, false);
    auto out = openvdb::gridPtrCast<openvdb::FloatGrid>(r.grid);
    ASSERT_TRUE(out);
    ASSERT_TRUE(isSlice(*out));
    const openvdb::Coord k = out->cbeginValueOn().getCoord();
    EXPECT_NEAR(out->indexToWorld(k)[2], 0.3, 1e-9); // the input's plane
    const Surface<2> curve = extractCurve(*out);
    double worst = 0;
    for (const auto& p : curve.points) {
        // phi^-1 of the new curve lies on the disc's circle.
        const Vec3d x = phi.inverse(Vec3d(p[0], p[1], 0.3)).x;
        worst = std::max(
            worst, std::abs(Vec3d(x[0] - discCentre[0], x[1] - discCentre[1], 0).length() - 0.6));
    }
    EXPECT_LT(worst, 0.02);

    const DeformationField phi3(swirlGrid(3, 4, 1.0, 0.25));
    EXPECT_THROW(transportGrid(*grid, phi3, false), openvdb::ValueError);
}

TEST(GridTransport, RejectsUnsupportedTypes)
{
    const DeformationField phi(swirlGrid(3, 4, 1.0, 0.25));
    auto ints = openvdb::Int32Grid::create(0);
    ints->tree().setValueOn(openvdb::Coord(1, 2, 3), 4);
    EXPECT_FALSE(isTransportableGrid(*ints));
    EXPECT_THROW(transportGrid(*ints, phi, false), openvdb::TypeError);
}

TEST(GridTransport, ResultDoesNotDependOnThreads)
{
    const DeformationField phi(swirlGrid(3, 5, 1.2, VOXEL));
    auto fog = linearFog(0.1, 5, 35, Vec3d(0.2, 0.1, -0.3));
    auto a = openvdb::gridPtrCast<openvdb::FloatGrid>(transportGrid(*fog, phi, false, true).grid);
    auto b = openvdb::gridPtrCast<openvdb::FloatGrid>(transportGrid(*fog, phi, false, false).grid);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->activeVoxelCount(), b->activeVoxelCount());
    auto bacc = b->getConstAccessor();
    for (auto v = a->cbeginValueOn(); v; ++v) {
        ASSERT_TRUE(bacc.isValueOn(v.getCoord()));
        ASSERT_EQ(*v, bacc.getValue(v.getCoord()));
    }
}

namespace {

/// max |g - f| over the voxels of f where f > 0.05, after carrying a Gaussian blob f (voxel
/// @a voxel) forward by phi and back by phi^-1.
double
blobRoundTripError(const DeformationField& phi, double voxel)
{
    const Vec3d c = phi.worldBounds().getCenter() + Vec3d(0.5, 0.0, 0.0);
    auto f = openvdb::FloatGrid::create(0.0f);
    f->setTransform(openvdb::math::Transform::createLinearTransform(voxel));
    f->setGridClass(openvdb::GRID_FOG_VOLUME);
    const int r = int(std::ceil(1.2 / voxel));
    const openvdb::Coord ci = openvdb::Coord::round(f->worldToIndex(c));
    auto acc = f->getAccessor();
    for (int k = -r; k <= r; ++k)
        for (int j = -r; j <= r; ++j)
            for (int i = -r; i <= r; ++i) {
                const openvdb::Coord ijk = ci.offsetBy(i, j, k);
                const double d2 = (f->indexToWorld(ijk) - c).lengthSqr();
                acc.setValueOn(ijk, float(std::exp(-d2 / (2 * 0.3 * 0.3))));
            }
    const GridTransportResult forward = transportGrid(*f, phi, false);
    const GridTransportResult back = transportGrid(*forward.grid, phi, true);
    auto g = openvdb::gridPtrCast<openvdb::FloatGrid>(back.grid);
    auto gacc = g->getConstAccessor();
    double worst = 0;
    for (auto v = f->cbeginValueOn(); v; ++v) {
        if (*v < 0.05f) continue;
        worst = std::max(worst, double(std::abs(gacc.getValue(v.getCoord()) - *v)));
    }
    return worst;
}

} // namespace

TEST(GridTransport, DensityForwardAndBackConvergesWithTheVoxelSize)
{
    // g = f o phi^-1, then g o phi: f again, up to two trilinear resamplings, O(h^2) in f's voxel.
    const DeformationField phi(swirlGrid(3, 5, 1.0, VOXEL));
    const double coarse = blobRoundTripError(phi, 0.1);
    const double fine = blobRoundTripError(phi, 0.05);
    EXPECT_LT(coarse, 0.1);
    EXPECT_LT(fine, coarse / 2.5) << "coarse " << coarse << " fine " << fine;
}
