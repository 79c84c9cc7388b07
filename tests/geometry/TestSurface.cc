/// @file TestSurface.cc
/// @brief Tests of explicit surfaces: checkSurface (closed, finite, non-degenerate), measures,
/// placement in Omega for 2D and 3D shapes.

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/Surface.h>
#include <vdbmatch/geometry/UnitBox.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

constexpr double EPS = 1e-12;

/// Expects checkSurface to throw a ValueError whose message contains @a text.
template <int D>
void
expectInvalid(const Surface<D>& s, const std::string& text)
{
    try {
        checkSurface(s, "shape 'x'");
        ADD_FAILURE() << "no exception, expected one containing '" << text << "'";
    } catch (const openvdb::ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(text), std::string::npos) << what;
        EXPECT_NE(what.find("shape 'x'"), std::string::npos) << what;
    }
}

} // namespace

TEST(Surface, ClosedShapesPass)
{
    EXPECT_NO_THROW(checkSurface(cubeMesh(), "cube"));
    EXPECT_NO_THROW(checkSurface(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 8, 16), "sphere"));
    Surface<2> two = circle(Vec<2>(0, 0), 1.0, 7);
    addCircle(two, Vec<2>(0, 0), 0.5, 5, /*clockwise=*/true);
    EXPECT_NO_THROW(checkSurface(two, "two circles"));
}

TEST(Surface, RejectsInvalidShapes)
{
    expectInvalid(Surface<3>(), "empty");
    expectInvalid(Surface<2>(), "empty");

    Surface<3> open = cubeMesh();
    open.elements.pop_back();
    expectInvalid(open, "not closed");

    Surface<3> nan = cubeMesh();
    nan.points[3][1] = std::numeric_limits<double>::quiet_NaN();
    expectInvalid(nan, "non-finite");

    Surface<3> outOfRange = cubeMesh();
    outOfRange.elements[0][2] = 8;
    expectInvalid(outOfRange, "refers to vertex 8");

    Surface<3> repeated = cubeMesh();
    repeated.elements[0][2] = repeated.elements[0][0];
    expectInvalid(repeated, "repeats vertex");

    // Two triangles glued back to back: closed but flat.
    Surface<3> flat;
    flat.points = {Vec<3>(0, 0, 0), Vec<3>(1, 0, 0), Vec<3>(0, 1, 0)};
    flat.elements = {{0, 1, 2}, {0, 2, 1}};
    expectInvalid(flat, "degenerate");

    Surface<2> openCurve = circle(Vec<2>(0, 0), 1.0, 6);
    openCurve.elements.pop_back();
    expectInvalid(openCurve, "not closed");

    Surface<2> line;
    line.points = {Vec<2>(0, 0), Vec<2>(1, 0)};
    line.elements = {{0, 1}, {1, 0}};
    expectInvalid(line, "degenerate");
}

TEST(Surface, MeasuresAndVolumes)
{
    const Surface<3> cube = cubeMesh(-1.0, 2.0);
    EXPECT_NEAR(measure(cube), 24.0, EPS);
    EXPECT_NEAR(signedVolume(cube), 8.0, EPS);
    // A square, counter-clockwise, then reversed.
    Surface<2> square;
    square.points = {Vec<2>(0, 0), Vec<2>(2, 0), Vec<2>(2, 2), Vec<2>(0, 2)};
    square.elements = {{0, 1}, {1, 2}, {2, 3}, {3, 0}};
    EXPECT_NEAR(measure(square), 8.0, EPS);
    EXPECT_NEAR(signedVolume(square), 4.0, EPS);
    for (auto& e : square.elements)
        std::swap(e[0], e[1]);
    EXPECT_NEAR(signedVolume(square), -4.0, EPS);
}

TEST(Surface, PlacementIn2D)
{
    // Two curves whose union box is [-1, 3] x [0, 1]: the x side (4) is scaled to 0.6.
    Surface<2> a;
    a.points = {Vec<2>(-1, 0), Vec<2>(1, 0), Vec<2>(1, 1)};
    a.elements = {{0, 1}, {1, 2}, {2, 0}};
    Surface<2> b = a;
    for (auto& p : b.points)
        p[0] += 2.0;
    const UnitBoxPlacement p = placeInUnitBox(a, b, 0.2);
    EXPECT_NEAR(p.scale, 0.6 / 4.0, EPS);
    const Surface<2> au = transformed(a, p, PlacementDirection::WorldToUnit);
    const Surface<2> bu = transformed(b, p, PlacementDirection::WorldToUnit);
    EXPECT_NEAR(au.points[0][0], 0.2, EPS);
    EXPECT_NEAR(bu.points[2][0], 0.8, EPS);
    // Centred in y: [0, 1] -> [0.5 - 0.075, 0.5 + 0.075].
    EXPECT_NEAR(au.points[0][1], 0.5 - 0.075, EPS);
    EXPECT_NEAR(au.points[2][1], 0.5 + 0.075, EPS);
    EXPECT_EQ(au.elements, a.elements);
    const Surface<2> back = transformed(au, p, PlacementDirection::UnitToWorld);
    for (size_t i = 0; i < a.points.size(); ++i)
        EXPECT_LT((back.points[i] - a.points[i]).norm(), 1e-12);

    const openvdb::BBoxd box = boundingBox(a);
    EXPECT_EQ(box.min(), openvdb::Vec3d(-1, 0, 0));
    EXPECT_EQ(box.max(), openvdb::Vec3d(1, 1, 0));
    EXPECT_THROW(placeInUnitBox(a, Surface<2>(), 0.2), openvdb::ValueError);
}

TEST(Surface, PlacementIn3D)
{
    const Surface<3> a = cubeMesh(0.0, 2.0), b = cubeMesh(1.0, 1.0);
    const UnitBoxPlacement p = placeInUnitBox(a, b, 0.25);
    EXPECT_NEAR(p.scale, 0.25, EPS);
    const Surface<3> au = transformed(a, p, PlacementDirection::WorldToUnit);
    const openvdb::BBoxd box = boundingBox(au);
    EXPECT_TRUE(box.min().eq(openvdb::Vec3d(0.25), EPS));
    EXPECT_TRUE(box.max().eq(openvdb::Vec3d(0.75), EPS));
}
