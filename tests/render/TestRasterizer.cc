/// @file TestRasterizer.cc
/// @brief The software renderers: a unit sphere covers a disc of the expected pixel area (±5%)
///        in orthographic and perspective views; the z-buffer hides a far triangle behind a near
///        one whatever the drawing order; a face seen head-on keeps its colour; fitCamera
///        centres the box; renderViews gives four non-blank views; renderCurves2D draws
///        coloured curves over grey grid lines. With VDBMATCH_RENDER_SAMPLES set, sample
///        pictures (textured sphere in four views, curves) are saved there.
#include "support/RenderSupport.h"

#include <vdbmatch/io/ImageIO.h>
#include <vdbmatch/render/Curves2D.h>
#include <vdbmatch/render/Rasterizer.h>
#include <vdbmatch/render/Texture.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <set>

using namespace vdbmatch;

namespace {

constexpr double PI = 3.14159265358979323846;
constexpr Rgb8 WHITE = {255, 255, 255};
constexpr Rgb8 RED = {255, 0, 0};
constexpr Rgb8 BLUE = {0, 0, 255};

int
countNonBackground(const Image8& image, const Rgb8& background)
{
    int n = 0;
    for (int y = 0; y < image.height; ++y) {
        for (int x = 0; x < image.width; ++x)
            n += image.at(x, y) != background;
    }
    return n;
}

} // namespace

TEST(Rasterizer, SphereDiscAreaOrthographic)
{
    const test::TriangleMesh sphere = test::uvSphere(1.0, 96, 48);
    Camera camera;
    camera.eye = openvdb::Vec3d(0.3, 0.2, 5.0);
    camera.target = openvdb::Vec3d(0.0);
    camera.orthoExtent = 4.0; // 200 px across 4 units: 50 px per unit
    RenderOptions options;
    options.supersample = false;
    const Image8 image = renderMesh(sphere.points, sphere.triangles, {}, camera, 200, 200, options);
    const double expected = PI * 50.0 * 50.0;
    EXPECT_NEAR(countNonBackground(image, WHITE), expected, 0.05 * expected);
    // The centre is lit, the corners are background.
    EXPECT_NE(image.at(100, 100), WHITE);
    EXPECT_EQ(image.at(2, 2), WHITE);
}

TEST(Rasterizer, SphereDiscAreaPerspective)
{
    const test::TriangleMesh sphere = test::uvSphere(1.0, 96, 48);
    Camera camera;
    camera.perspective = true;
    camera.eye = openvdb::Vec3d(0.0, 0.0, 4.0);
    camera.fovDegrees = 40.0;
    const Image8 image = renderMesh(sphere.points, sphere.triangles, {}, camera, 240, 160);
    // Silhouette half-angle asin(1/4); radius f tan(asin(1/4)), f = 80 / tan(20 deg).
    const double f = 80.0 / std::tan(20.0 * PI / 180.0);
    const double r = f * std::tan(std::asin(0.25));
    const double expected = PI * r * r;
    // Supersampled edges: count half-covered pixels too, so allow the rim.
    EXPECT_NEAR(countNonBackground(image, WHITE), expected, 0.05 * expected);
}

TEST(Rasterizer, ZBufferOcclusion)
{
    // A small red triangle at z = +1 in front of a large blue one at z = -1 (camera at z = +5).
    const std::vector<openvdb::Vec3d> points = {{-0.5, -0.5, 1.0}, {0.5, -0.5, 1.0},
                                                {0.0, 0.5, 1.0},   {-2.0, -2.0, -1.0},
                                                {2.0, -2.0, -1.0}, {0.0, 2.0, -1.0}};
    const std::vector<Rgb8> colors = {RED, RED, RED, BLUE, BLUE, BLUE};
    Camera camera;
    camera.orthoExtent = 5.0;
    for (const bool perspective : {false, true}) {
        camera.perspective = perspective;
        for (const bool nearFirst : {true, false}) {
            const std::vector<std::array<std::int32_t, 3>> triangles =
                nearFirst ? std::vector<std::array<std::int32_t, 3>>{{0, 1, 2}, {3, 4, 5}}
                          : std::vector<std::array<std::int32_t, 3>>{{3, 4, 5}, {0, 1, 2}};
            const Image8 image = renderMesh(points, triangles, colors, camera, 100, 100);
            // Faces seen head-on keep their full colour.
            EXPECT_EQ(image.at(50, 50), RED) << "perspective " << perspective;
            // Off-axis, the perspective headlight is slightly oblique.
            const Rgb8 far = image.at(50, 20);
            EXPECT_EQ(far[0], 0);
            EXPECT_GE(far[2], perspective ? 245 : 255) << "perspective " << perspective;
            EXPECT_EQ(image.at(2, 2), WHITE);
        }
    }
}

TEST(Rasterizer, CameraFraming)
{
    const openvdb::BBoxd box(openvdb::Vec3d(1.0, 2.0, 3.0), openvdb::Vec3d(3.0, 4.0, 7.0));
    for (const bool perspective : {false, true}) {
        const Camera camera =
            fitCamera(box, openvdb::Vec3d(-1, -1, -1), openvdb::Vec3d(0, 1, 0), perspective);
        const Projector projector(camera, 300, 200);
        ProjectedPoint p;
        ASSERT_TRUE(projector.project(box.getCenter(), p));
        EXPECT_NEAR(p.x, 150.0, 1e-9);
        EXPECT_NEAR(p.y, 100.0, 1e-9);
        // Every corner lies inside the image.
        for (int i = 0; i < 8; ++i) {
            const openvdb::Vec3d corner(i & 1 ? box.max().x() : box.min().x(),
                                        i & 2 ? box.max().y() : box.min().y(),
                                        i & 4 ? box.max().z() : box.min().z());
            ASSERT_TRUE(projector.project(corner, p));
            EXPECT_GT(p.x, 0.0);
            EXPECT_LT(p.x, 300.0);
            EXPECT_GT(p.y, 0.0);
            EXPECT_LT(p.y, 200.0);
        }
    }
    // y up: a point above the centre is drawn above it.
    const Camera front = fitCamera(box, openvdb::Vec3d(0, 0, -1), openvdb::Vec3d(0, 1, 0));
    ProjectedPoint above;
    ASSERT_TRUE(
        Projector(front, 100, 100).project(box.getCenter() + openvdb::Vec3d(0, 1, 0), above));
    EXPECT_LT(above.y, 50.0);
    EXPECT_THROW(fitCamera(box, openvdb::Vec3d(0, 1, 0), openvdb::Vec3d(0, 2, 0)),
                 openvdb::ValueError);
    EXPECT_THROW(fitCamera(box, openvdb::Vec3d(0.0), openvdb::Vec3d(0, 1, 0)), openvdb::ValueError);
}

TEST(Rasterizer, RejectsBadInput)
{
    const std::vector<openvdb::Vec3d> points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    EXPECT_THROW(renderMesh(points, {{0, 1, 3}}, {}, Camera(), 10, 10), openvdb::ValueError);
    EXPECT_THROW(renderMesh(points, {{0, 1, 2}}, {RED}, Camera(), 10, 10), openvdb::ValueError);
    EXPECT_THROW(renderMesh(points, {{0, 1, 2}}, {}, Camera(), 0, 10), openvdb::ValueError);
}

TEST(Rasterizer, FourViewsOfATexturedSphere)
{
    // An ellipsoid-like sphere off the origin, so that the views differ.
    test::TriangleMesh mesh = test::uvSphere(1.0, 64, 32, openvdb::Vec3d(2.0, -1.0, 0.5));
    for (auto& p : mesh.points)
        p.x() = 2.0 + 1.6 * (p.x() - 2.0);
    SurfaceTexture texture;
    texture.pattern = SurfacePattern::Checker;
    const std::vector<Rgb8> colors = paintSurface(mesh.points, texture);
    constexpr int VIEW = 160;
    const Image8 image = renderViews(mesh.points, mesh.triangles, colors, VIEW);
    EXPECT_EQ(image.width, 4 * VIEW + 3);
    EXPECT_EQ(image.height, VIEW);
    for (int v = 0; v < 4; ++v) {
        std::set<int> colours;
        int covered = 0;
        for (int y = 0; y < VIEW; ++y) {
            for (int x = 0; x < VIEW; ++x) {
                const Rgb8 c = image.at(v * (VIEW + 1) + x, y);
                covered += c != WHITE;
                colours.insert(c[0] << 16 | c[1] << 8 | c[2]);
            }
        }
        EXPECT_GT(covered, VIEW * VIEW / 8) << "view " << v;
        EXPECT_GT(colours.size(), 20u) << "view " << v;
    }
    const std::string samples = test::sampleDirectory();
    if (!samples.empty()) {
        writePng(samples + "/sphere_views.png", image.width, image.height, image.rgb);
        texture.pattern = SurfacePattern::Position;
        const Image8 persp = renderViews(mesh.points, mesh.triangles,
                                         paintSurface(mesh.points, texture), 256, {}, true);
        writePng(samples + "/sphere_views_position_perspective.png", persp.width, persp.height,
                 persp.rgb);
    }
}

TEST(Rasterizer, Curves2D)
{
    // A unit circle, painted by angle, over a grid of lines x, y = -1.5 .. 1.5 step 0.5.
    ColoredPolyline2D circle;
    for (int i = 0; i < 200; ++i) {
        const double a = 2.0 * PI * i / 200;
        circle.points.emplace_back(std::cos(a), std::sin(a));
    }
    CurveTexture texture;
    texture.angleCells = 8;
    circle.colors = paintCurve(circle.points, texture);
    std::vector<std::vector<openvdb::Vec2d>> grid;
    for (int k = -3; k <= 3; ++k) {
        grid.push_back({{-1.5, 0.5 * k}, {1.5, 0.5 * k}});
        grid.push_back({{0.5 * k, -1.5}, {0.5 * k, 1.5}});
    }
    const Image8 image = renderCurves2D({circle}, grid, openvdb::Vec2d(-1.5, -1.5),
                                        openvdb::Vec2d(1.5, 1.5), 300, 200);
    ASSERT_EQ(image.width, 300);
    ASSERT_EQ(image.height, 200);
    // Frame: 3 units across 200 - 2 * 8 = 184 px, centred at (150, 100); y up.
    const double scale = 184.0 / 3.0;
    auto pixel = [&](double x, double y) {
        return image.at(int(150 + scale * x), int(100 - scale * y));
    };
    // Points on the circle: angle a falls in band floor((a + pi) / (2 pi) * 8); even bands are
    // colour A. 0.6 rad: band 4 (A); 1.2 rad: band 5 (B); pi/2 + 0.2: band 6 (A).
    EXPECT_EQ(pixel(std::cos(0.5 * PI + 0.2), std::sin(0.5 * PI + 0.2)), texture.colorA);
    EXPECT_EQ(pixel(std::cos(0.6), std::sin(0.6)), texture.colorA);
    EXPECT_EQ(pixel(std::cos(1.2), std::sin(1.2)), texture.colorB);
    // Grid line x = 0.5 away from the circle is grey; the space between lines is white.
    const Rgb8 grid05 = pixel(0.5, -1.25);
    EXPECT_LT(grid05[0], 230);
    EXPECT_EQ(grid05[0], grid05[2]);
    EXPECT_EQ(pixel(0.25, -1.25), WHITE);

    const std::string samples = test::sampleDirectory();
    if (!samples.empty()) writePng(samples + "/curves.png", image.width, image.height, image.rgb);
}
