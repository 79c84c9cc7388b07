/// @file TestTransportedTexture.cc
/// @brief A texture painted on M1 and carried by a deformation: under phi = Id the images equal
///        the source and the grid lines stay straight; under a translation (constant
///        displacement inside Omega) the vertices move by it; the colours never change; loops
///        are recovered from unordered segments; dimension mismatches throw.
#include <vdbmatch/eval/TransportedTexture.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>
#include <openvdb/openvdb.h>

#include <cmath>
#include <random>

using namespace vdbmatch;

namespace {

constexpr double VOXEL = 0.125; ///< world units
constexpr int N = 16;           ///< voxels across Omega: Omega = [-1, 1]^D
constexpr double OMEGA_MIN = -1.0;

/// A displacement grid over [-1, 1]^D (2D: the layer k = 0): @a inside on every voxel at least
/// @a border voxels from the boundary, 0 elsewhere.
openvdb::Vec3SGrid::Ptr
displacementGrid(int dim, const openvdb::Vec3s& inside, int border = 1)
{
    openvdb::Vec3SGrid::Ptr grid = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    openvdb::math::Transform::Ptr xform = openvdb::math::Transform::createLinearTransform(VOXEL);
    xform->postTranslate(openvdb::Vec3d(OMEGA_MIN));
    grid->setTransform(xform);
    grid->setName("displacement");
    auto acc = grid->getAccessor();
    const int kMax = dim == 3 ? N : 0;
    for (int i = 0; i <= N; ++i) {
        for (int j = 0; j <= N; ++j) {
            for (int k = 0; k <= kMax; ++k) {
                bool interior = i >= border && i <= N - border && j >= border && j <= N - border;
                if (dim == 3) interior = interior && k >= border && k <= N - border;
                acc.setValueOn(openvdb::Coord(i, j, k), interior ? inside : openvdb::Vec3s(0.0f));
            }
        }
    }
    return grid;
}

/// An octahedron-like closed mesh around the origin, radius r.
Surface<3>
octahedron(double r)
{
    Surface<3> s;
    const double v[6][3] = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
    for (const auto& p : v)
        s.points.push_back(Vec<3>(p[0], p[1], p[2]));
    s.elements = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                  {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    return s;
}

/// A circle of @a n points, radius r, its segments listed in a scrambled order.
Surface<2>
circle(int n, double r)
{
    Surface<2> s;
    for (int i = 0; i < n; ++i) {
        const double a = 2.0 * M_PI * i / n;
        s.points.push_back(Vec<2>(r * std::cos(a), r * std::sin(a)));
    }
    for (int i = 0; i < n; ++i) {
        const int k = (i * 7) % n; // 7 is coprime with the n used below
        s.elements.push_back({(k + 1) % n, k});
    }
    return s;
}

} // namespace

TEST(TransportedTexture, IdentitySurface)
{
    openvdb::initialize();
    const DeformationField phi(displacementGrid(3, openvdb::Vec3s(0.0f)));
    const Surface<3> m1 = octahedron(0.5);
    const TransportedSurface t = transportSurface(m1, SurfaceTexture{}, phi, &phi);
    ASSERT_EQ(t.source.size(), m1.points.size());
    ASSERT_EQ(t.deformed.size(), m1.points.size());
    ASSERT_EQ(t.roundtrip.size(), m1.points.size());
    EXPECT_EQ(t.triangles.size(), m1.elements.size());
    EXPECT_EQ(t.colors, paintSurface(t.source, SurfaceTexture{}));
    for (std::size_t i = 0; i < t.source.size(); ++i) {
        EXPECT_LT((t.deformed[i] - t.source[i]).length(), 1e-12);
        EXPECT_LT((t.roundtrip[i] - t.source[i]).length(), 1e-12);
    }
}

TEST(TransportedTexture, TranslationSurface)
{
    openvdb::initialize();
    const openvdb::Vec3s shift(0.05f, -0.1f, 0.02f);
    const DeformationField phi(displacementGrid(3, shift, 2));
    const DeformationField back(displacementGrid(3, -shift, 2));
    const Surface<3> m1 = octahedron(0.5); // far from the boundary layers of the grids
    const TransportedSurface t = transportSurface(m1, SurfaceTexture{}, phi, &back);
    const TransportedSurface noPsi = transportSurface(m1, SurfaceTexture{}, phi);
    EXPECT_TRUE(noPsi.roundtrip.empty());
    for (std::size_t i = 0; i < t.source.size(); ++i) {
        EXPECT_LT((t.deformed[i] - t.source[i] - openvdb::Vec3d(shift)).length(), 1e-6);
        EXPECT_LT((t.roundtrip[i] - t.source[i]).length(), 1e-6);
    }
    // The colours are those of M1, not repainted on the moved points.
    EXPECT_EQ(t.colors, paintSurface(t.source, SurfaceTexture{}));
}

TEST(TransportedTexture, ClosedLoops)
{
    const Surface<2> c = circle(12, 0.5);
    const auto loops = closedLoops(c);
    ASSERT_EQ(loops.size(), 1u);
    ASSERT_EQ(loops[0].size(), 12u);
    // Consecutive loop vertices are neighbours on the circle.
    for (std::size_t i = 0; i < 12; ++i) {
        const int a = loops[0][i], b = loops[0][(i + 1) % 12];
        EXPECT_TRUE((a - b + 12) % 12 == 1 || (b - a + 12) % 12 == 1) << a << " " << b;
    }
    Surface<2> open = c;
    open.elements.pop_back();
    EXPECT_THROW(closedLoops(open), openvdb::ValueError);
}

TEST(TransportedTexture, IdentityCurveAndStraightGrid)
{
    openvdb::initialize();
    const DeformationField phi(displacementGrid(2, openvdb::Vec3s(0.0f)));
    ASSERT_EQ(phi.dimension(), 2);
    const Surface<2> m1 = circle(40 - 3, 0.4); // 37 points: 7 is coprime
    CurveTexture texture;
    texture.pattern = CurvePattern::ArcLengthStripes;
    texture.stripeWidth = 0.2;
    constexpr int CELLS = 8;
    const TransportedCurve t = transportCurve(m1, texture, phi, &phi, CELLS);
    ASSERT_EQ(t.source.size(), 1u);
    ASSERT_EQ(t.deformed.size(), 1u);
    ASSERT_EQ(t.roundtrip.size(), 1u);
    EXPECT_EQ(t.deformed[0].colors, t.source[0].colors);
    EXPECT_EQ(t.roundtrip[0].colors, t.source[0].colors);
    EXPECT_EQ(t.source[0].colors, paintCurve(t.source[0].points, texture));
    for (std::size_t i = 0; i < t.source[0].points.size(); ++i) {
        EXPECT_LT((t.deformed[0].points[i] - t.source[0].points[i]).length(), 1e-12);
    }
    EXPECT_EQ(t.omegaMin, openvdb::Vec2d(-1.0));
    EXPECT_EQ(t.omegaMax, openvdb::Vec2d(1.0));

    ASSERT_EQ(t.grid.size(), std::size_t(2 * (CELLS + 1)));
    ASSERT_EQ(t.deformedGrid.size(), t.grid.size());
    ASSERT_EQ(t.roundtripGrid.size(), t.grid.size());
    for (std::size_t l = 0; l < t.grid.size(); ++l) {
        const auto& line = t.grid[l];
        const int axis = l <= CELLS ? 0 : 1; // x = const, then y = const
        const double c = -1.0 + 2.0 * double(l % (CELLS + 1)) / CELLS;
        ASSERT_GE(line.size(), std::size_t(N + 1)); // at least every voxel edge
        EXPECT_DOUBLE_EQ(line.front()[1 - axis], -1.0);
        EXPECT_DOUBLE_EQ(line.back()[1 - axis], 1.0);
        for (std::size_t i = 0; i < line.size(); ++i) {
            EXPECT_NEAR(line[i][axis], c, 1e-12);
            if (i) {
                EXPECT_GT(line[i][1 - axis], line[i - 1][1 - axis]);
            }
            // The images under the identity are the same straight lines.
            EXPECT_LT((t.deformedGrid[l][i] - line[i]).length(), 1e-12);
        }
        for (const auto& p : t.roundtripGrid[l])
            EXPECT_NEAR(p[axis], c, 1e-12);
    }
}

TEST(TransportedTexture, TranslationCurveAndExactGrid)
{
    openvdb::initialize();
    const openvdb::Vec3s shift(0.1f, 0.05f, 0.0f);
    const DeformationField phi(displacementGrid(2, shift, 2));
    const Surface<2> m1 = circle(37, 0.4);
    const TransportedCurve t = transportCurve(m1, CurveTexture{}, phi, nullptr, 4);
    EXPECT_TRUE(t.roundtrip.empty());
    EXPECT_TRUE(t.roundtripGrid.empty());
    for (std::size_t i = 0; i < t.source[0].points.size(); ++i) {
        const openvdb::Vec2d d = t.deformed[0].points[i] - t.source[0].points[i];
        EXPECT_NEAR(d.x(), 0.1, 1e-6);
        EXPECT_NEAR(d.y(), 0.05, 1e-6);
    }
    // The middle line x = 0 moves by the shift away from the boundary layers.
    const auto& line = t.grid[2];
    const auto& image = t.deformedGrid[2];
    for (std::size_t i = 0; i < line.size(); ++i) {
        if (std::abs(line[i].y()) < 1.0 - 2 * VOXEL - 1e-9) {
            EXPECT_NEAR(image[i].x() - line[i].x(), 0.1, 1e-6);
            EXPECT_NEAR(image[i].y() - line[i].y(), 0.05, 1e-6);
        }
    }
}

TEST(TransportedTexture, GridLinesAreExactCorners)
{
    // A random piecewise-linear phi: between consecutive samples of a grid line the map must be
    // affine, so the image of a midpoint is the midpoint of the images.
    openvdb::initialize();
    openvdb::Vec3SGrid::Ptr grid = displacementGrid(2, openvdb::Vec3s(0.0f));
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> uniform(-0.2f * float(VOXEL), 0.2f * float(VOXEL));
    for (auto it = grid->beginValueOn(); it; ++it)
        it.setValue(openvdb::Vec3s(uniform(rng), uniform(rng), 0.0f));
    const DeformationField phi(grid);
    const auto lines = gridLines(phi, 5); // 5 cells: lines off the voxel edges
    for (const auto& line : lines) {
        const std::vector<openvdb::Vec2d> image = applyToPolyline(phi, line);
        for (std::size_t i = 0; i + 1 < line.size(); ++i) {
            const openvdb::Vec2d mid = 0.5 * (line[i] + line[i + 1]);
            const openvdb::Vec3d m = phi.apply(openvdb::Vec3d(mid.x(), mid.y(), 0.0));
            const openvdb::Vec2d expected = 0.5 * (image[i] + image[i + 1]);
            EXPECT_NEAR(m.x(), expected.x(), 1e-6);
            EXPECT_NEAR(m.y(), expected.y(), 1e-6);
        }
    }
}

TEST(TransportedTexture, DimensionMismatchThrows)
{
    openvdb::initialize();
    const DeformationField phi2(displacementGrid(2, openvdb::Vec3s(0.0f)));
    const DeformationField phi3(displacementGrid(3, openvdb::Vec3s(0.0f)));
    EXPECT_THROW(transportSurface(octahedron(0.5), SurfaceTexture{}, phi2), openvdb::ValueError);
    EXPECT_THROW(transportSurface(octahedron(0.5), SurfaceTexture{}, phi3, &phi2),
                 openvdb::ValueError);
    EXPECT_THROW(transportCurve(circle(37, 0.4), CurveTexture{}, phi3), openvdb::ValueError);
    EXPECT_THROW(transportCurve(circle(37, 0.4), CurveTexture{}, phi2, nullptr, 0),
                 openvdb::ValueError);
}
