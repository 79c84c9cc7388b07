/// @file TestTexture.cc
/// @brief Per-vertex texture patterns: the spherical checker gives both colours in balanced
///        amounts and alternates between neighbouring cells; longitude and axis stripes follow
///        their documented bands; position colours span the bounding box; curve patterns by
///        angle and arc length; bad parameters throw.
#include "support/RenderSupport.h"

#include <vdbmatch/render/Texture.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <limits>

using namespace vdbmatch;

namespace {

constexpr double PI = 3.14159265358979323846;

double
fraction(const std::vector<Rgb8>& colors, const Rgb8& c)
{
    double n = 0;
    for (const auto& x : colors)
        n += x == c;
    return n / colors.size();
}

} // namespace

TEST(Texture, SphericalChecker)
{
    const openvdb::Vec3d centre(1.0, 2.0, 3.0);
    const test::TriangleMesh mesh = test::uvSphere(2.0, 60, 30, centre);
    SurfaceTexture texture;
    texture.pattern = SurfacePattern::Checker;
    texture.longitudeCells = 12;
    texture.latitudeCells = 6;
    const std::vector<Rgb8> colors = paintSurface(mesh.points, texture);
    ASSERT_EQ(colors.size(), mesh.points.size());
    EXPECT_NEAR(fraction(colors, texture.colorA), 0.5, 0.1);
    EXPECT_NEAR(fraction(colors, texture.colorB), 0.5, 0.1);
    EXPECT_DOUBLE_EQ(fraction(colors, texture.colorA) + fraction(colors, texture.colorB), 1.0);

    // Pole axis y: longitude measured in the z-x plane. Two points on the equator 30 degrees
    // apart (centres of neighbouring cells) differ, and so do two at the same longitude in
    // neighbouring latitude bands.
    auto at = [&](double lon, double lat) {
        // longitude = atan2(d[x], d[z]) for axis 1 (u = z, v = x).
        const openvdb::Vec3d d(std::cos(lat) * std::sin(lon), std::sin(lat),
                               std::cos(lat) * std::cos(lon));
        SurfaceTexture centred = texture;
        centred.center = centre;
        return paintSurface({centre + d}, centred)[0];
    };
    const double cell = 2.0 * PI / 12;
    EXPECT_NE(at(0.5 * cell, 0.1), at(1.5 * cell, 0.1));
    EXPECT_NE(at(0.5 * cell, 0.1), at(0.5 * cell, -0.4));
    EXPECT_EQ(at(0.5 * cell, 0.1), at(2.5 * cell, 0.1));
}

TEST(Texture, StripesAndPosition)
{
    const test::TriangleMesh mesh = test::uvSphere(1.0, 40, 20);
    SurfaceTexture texture;
    texture.pattern = SurfacePattern::LongitudeStripes;
    texture.longitudeCells = 8;
    const std::vector<Rgb8> stripes = paintSurface(mesh.points, texture);
    EXPECT_NEAR(fraction(stripes, texture.colorA), 0.5, 0.1);

    texture.pattern = SurfacePattern::AxisStripes;
    texture.axis = 0;
    texture.stripeWidth = 0.5;
    // Bands from x = -1: [-1, -0.5) A, [-0.5, 0) B, [0, 0.5) A, [0.5, 1] B.
    const std::vector<openvdb::Vec3d> points = {{-1.0, 0, 0}, {-0.75, 0, 0}, {-0.25, 0, 0},
                                                {0.25, 5, 0}, {0.75, 0, -3}, {1.0, 0, 0}};
    const std::vector<Rgb8> slabs = paintSurface(points, texture);
    EXPECT_EQ(slabs[1], texture.colorA);
    EXPECT_EQ(slabs[2], texture.colorB);
    EXPECT_EQ(slabs[3], texture.colorA);
    EXPECT_EQ(slabs[4], texture.colorB);

    texture.pattern = SurfacePattern::Position;
    const std::vector<Rgb8> position = paintSurface({{0, 0, 0}, {2, 4, 6}, {1, 2, 3}}, texture);
    EXPECT_EQ(position[0], (Rgb8{0, 0, 0}));
    EXPECT_EQ(position[1], (Rgb8{255, 255, 255}));
    EXPECT_EQ(position[2], (Rgb8{128, 128, 128}));

    texture.axis = 3;
    EXPECT_THROW(paintSurface(points, texture), openvdb::ValueError);
    texture.axis = 0;
    texture.stripeWidth = 0.0;
    EXPECT_THROW(paintSurface(points, texture), openvdb::ValueError);
}

TEST(Texture, Curves)
{
    std::vector<openvdb::Vec2d> circle;
    for (int i = 0; i < 400; ++i) {
        const double a = 2.0 * PI * (i + 0.5) / 400;
        circle.emplace_back(3.0 + std::cos(a), -1.0 + std::sin(a));
    }
    CurveTexture texture;
    texture.pattern = CurvePattern::AngleStripes;
    texture.angleCells = 4;
    const std::vector<Rgb8> byAngle = paintCurve(circle, texture);
    EXPECT_NEAR(fraction(byAngle, texture.colorA), 0.5, 0.01);
    // Angle in [0, 90) degrees is band 2 (of 4, counted from -180): colour A; [90, 180) is B.
    EXPECT_EQ(byAngle[50], texture.colorA);
    EXPECT_EQ(byAngle[150], texture.colorB);

    texture.pattern = CurvePattern::ArcLengthStripes;
    texture.stripeWidth = 2.0 * PI / 10; // ten bands around the unit circle
    const std::vector<Rgb8> byLength = paintCurve(circle, texture);
    EXPECT_EQ(byLength[0], texture.colorA);
    EXPECT_EQ(byLength[20], texture.colorA);
    EXPECT_EQ(byLength[60], texture.colorB);
    EXPECT_NEAR(fraction(byLength, texture.colorA), 0.5, 0.02);

    texture.pattern = CurvePattern::Position;
    const std::vector<Rgb8> position = paintCurve({{0, 0}, {1, 1}}, texture);
    EXPECT_EQ(position[0], (Rgb8{0, 0, 255}));
    EXPECT_EQ(position[1], (Rgb8{255, 255, 0}));

    texture.angleCells = 0;
    EXPECT_THROW(paintCurve(circle, texture), openvdb::ValueError);
}

TEST(Texture, NonFinitePointsAreGrey)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    SurfaceTexture texture;
    texture.pattern = SurfacePattern::Position;
    const std::vector<Rgb8> colors = paintSurface({{0, 0, 0}, {nan, 0, 0}, {2, 2, 2}}, texture);
    EXPECT_EQ(colors[1], (Rgb8{128, 128, 128}));
    EXPECT_EQ(colors[2], (Rgb8{255, 255, 255}));
    texture.pattern = SurfacePattern::AxisStripes;
    texture.stripeWidth = 1e-300; // floor() far beyond the range of any integer type
    EXPECT_NO_THROW(paintSurface({{0, 0, 0}, {1e10, 0, 0}}, texture));
    CurveTexture curve;
    curve.pattern = CurvePattern::ArcLengthStripes;
    EXPECT_EQ(paintCurve({{0, 0}, {nan, 1}, {0.05, 0}}, curve)[1], (Rgb8{128, 128, 128}));
}
