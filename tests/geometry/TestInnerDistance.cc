/// @file TestInnerDistance.cc
/// @brief F, the inner distance from given points (geometry/InnerDistance.h): the distance from
///        the centre of a disc and a ball in every direction (the eikonal solver's error does
///        not depend on the direction, unlike an 8-neighbour graph's 8% along 22.5 degrees), the
///        path round the slot of a U rather than across it (outside too, next to the far
///        prong), a turn of the shape and its sources turning F with them, a finite
///        continuation outside (1-Lipschitz outside a disc), the interpolant's gradient,
///        thread-count independence, bad input, and a point's own source (the nearer end of a
///        bar, none in its middle).

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/InnerDistance.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <random>
#include <vector>

using namespace vdbmatch;
using namespace vdbmatch::test;

TEST(InnerDistance, DistanceFromTheCentreOfADiscInEveryDirection)
{
    const Vec<2> c(0.5, 0.5);
    const Surface<2> disc = circle(c, 0.35, 400);
    const InnerDistanceField<2> f = innerDistanceFields<2>(disc, {c}, 8)[0];
    ASSERT_FALSE(f.empty());
    EXPECT_EQ(f.reachedInside, f.insideNodes);
    double worst = 0;
    for (double deg = 0; deg <= 45; deg += 7.5) {
        const double a = deg * M_PI / 180;
        for (double r : {0.1, 0.2, 0.3}) {
            const Vec<2> x = c + r * Vec<2>(std::cos(a), std::sin(a));
            Real v;
            ASSERT_TRUE(f.sample(x, v));
            worst = std::max(worst, std::abs(v - r));
        }
    }
    // First-order fast marching from a point: about a cell; an 8-neighbour graph is 0.025 off
    // at r = 0.3 along 22.5 degrees.
    EXPECT_LT(worst, 2 * f.h);
}

TEST(InnerDistance, DistanceFromTheCentreOfABall)
{
    const Vec<3> c(0.5, 0.5, 0.5);
    const Surface<3> ball = uvSphere(c, 0.35, 40, 80);
    const InnerDistanceField<3> f = innerDistanceFields<3>(ball, {c}, 6)[0];
    ASSERT_FALSE(f.empty());
    double worst = 0;
    const std::vector<Vec<3>> directions{Vec<3>(1, 0, 0), Vec<3>(1, 1, 0).normalized(),
                                         Vec<3>(1, 1, 1).normalized(),
                                         Vec<3>(1, 0.4, 0.2).normalized()};
    for (const Vec<3>& d : directions) {
        for (double r : {0.1, 0.2, 0.3}) {
            Real v;
            ASSERT_TRUE(f.sample(c + r * d, v));
            worst = std::max(worst, std::abs(v - r));
        }
    }
    EXPECT_LT(worst, 2 * f.h);
}

TEST(InnerDistance, RunsRoundTheSlotOfAU)
{
    // A U: two prongs 0.1 wide, 0.5 long, joined by a base 0.1 high; the slot is 0.1 wide.
    const Surface<2> u =
        polygon({Vec<2>(0.2, 0.2), Vec<2>(0.5, 0.2), Vec<2>(0.5, 0.8), Vec<2>(0.4, 0.8),
                 Vec<2>(0.4, 0.3), Vec<2>(0.3, 0.3), Vec<2>(0.3, 0.8), Vec<2>(0.2, 0.8)},
                0.005);
    const Vec<2> tipA(0.25, 0.75), tipB(0.45, 0.75);
    const InnerDistanceField<2> f = innerDistanceFields<2>(u, {tipA}, 8)[0];
    Real atB;
    ASSERT_TRUE(f.sample(tipB, atB));
    // Down one prong, across the base, up the other: 0.5 + 0.2 + 0.5 = 1.2 along the axes,
    // cut at the corners (the shortest path inside hugs them): about 0.45 + 0.1 + 0.45 + 0.14.
    EXPECT_GT(atB, 0.9);
    EXPECT_LT(atB, 1.2);
    // The straight way across the slot is 0.2.
    EXPECT_GT(atB, 4 * (tipB - tipA).norm());
    // Outside, F is continued from the nearer side: in the slot next to prong A, F of A's face
    // plus the distance to it (the straight distance from the tip to the face, inside A)...
    Real inSlot;
    const Vec<2> x(0.31, 0.7), face(0.3, 0.7);
    ASSERT_TRUE(f.sample(x, inSlot));
    EXPECT_NEAR(inSlot, (face - tipA).norm() + 0.01, 3 * f.h);
    // ... and on prong B's face, and just outside it in the slot, the path round the U, not
    // the 0.16 straight across the slot from A's tip, which a march of F itself outside would
    // bring there (and then into the interpolant at the face's points).
    for (const Vec<2>& y : {Vec<2>(0.4, 0.7), Vec<2>(0.397, 0.7), Vec<2>(0.39, 0.7)}) {
        Real v;
        ASSERT_TRUE(f.sample(y, v));
        EXPECT_GT(v, 0.8) << y.transpose();
        EXPECT_GT(v, 4 * (y - tipA).norm()) << y.transpose();
    }
}

TEST(InnerDistance, TurnsWithTheShapeAndItsSources)
{
    const Vec<2> c(0.5, 0.5);
    const std::vector<double> arms{0.38, 0.25, 0.33, 0.3, 0.36};
    const Surface<2> a = starCurve(c, arms, 0.09, 0.1);
    const double turn = 0.4; // radians
    const Surface<2> b = starCurve(c, arms, 0.09, 0.1 + turn);
    const Eigen::Rotation2D<double> rotate(turn);
    const std::vector<Vec<2>> sa{c + Vec<2>(0.3 * std::cos(0.1), 0.3 * std::sin(0.1))};
    const std::vector<Vec<2>> sb{c + rotate * (sa[0] - c)};
    const InnerDistanceField<2> fa = innerDistanceFields<2>(a, sa, 8)[0];
    const InnerDistanceField<2> fb = innerDistanceFields<2>(b, sb, 8)[0];
    double worst = 0, largest = 0;
    for (const Vec<2>& x : a.points) {
        const Vec<2> x1 = c + 0.9 * (x - c); // inside, away from the outline's corners
        Real va, vb;
        ASSERT_TRUE(fa.sample(x1, va));
        ASSERT_TRUE(fb.sample(c + rotate * (x1 - c), vb));
        worst = std::max(worst, std::abs(va - vb));
        largest = std::max(largest, va);
    }
    EXPECT_GT(largest, 0.5);
    EXPECT_LT(worst, 3 * fa.h);
}

TEST(InnerDistance, ContinuedOutsideFiniteAndLipschitz)
{
    const Surface<2> disc = circle(Vec<2>(0.4, 0.55), 0.2, 300);
    const InnerDistanceField<2> f = innerDistanceFields<2>(disc, {Vec<2>(0.3, 0.5)}, 7)[0];
    for (Real v : f.values)
        ASSERT_TRUE(std::isfinite(v));
    // Neighbouring nodes differ by at most a cell (the eikonal update never exceeds m + h).
    for (int j = 0; j <= f.n; ++j) {
        for (int i = 0; i < f.n; ++i) {
            const std::size_t k = std::size_t(j * (f.n + 1) + i);
            EXPECT_LE(std::abs(f.values[k + 1] - f.values[k]), f.h + 1e-6); // stored as floats
        }
    }
    // Points beyond the box are clamped to it.
    Real in, out;
    Vec<2> g;
    ASSERT_TRUE(f.sample(Vec<2>(1, 0.5), in));
    ASSERT_TRUE(f.sample(Vec<2>(1.3, 0.5), out, &g));
    EXPECT_EQ(in, out);
    EXPECT_EQ(g[0], 0);
}

TEST(InnerDistance, GradientOfTheInterpolant)
{
    const Surface<3> ball = uvSphere(Vec<3>(0.5, 0.45, 0.5), 0.3, 20, 40);
    const InnerDistanceField<3> f = innerDistanceFields<3>(ball, {Vec<3>(0.4, 0.5, 0.5)}, 5)[0];
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> U(0.1, 0.9);
    for (int k = 0; k < 50; ++k) {
        const Vec<3> x(U(rng), U(rng), U(rng));
        Real v;
        Vec<3> g;
        ASSERT_TRUE(f.sample(x, v, &g));
        for (int a = 0; a < 3; ++a) {
            const Real eps = 1e-7;
            Vec<3> dx = Vec<3>::Zero();
            dx[a] = eps;
            Real vp, vm;
            f.sample(x + dx, vp);
            f.sample(x - dx, vm);
            EXPECT_NEAR((vp - vm) / (2 * eps), g[a], 1e-6) << "point " << k << " axis " << a;
        }
    }
}

TEST(InnerDistance, SameWithAndWithoutThreads)
{
    const Surface<3> ball = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 20, 40);
    const std::vector<Vec<3>> s{Vec<3>(0.3, 0.5, 0.5), Vec<3>(0.7, 0.52, 0.5)};
    const std::vector<InnerDistanceField<3>> a = innerDistanceFields<3>(ball, s, 6, true);
    const std::vector<InnerDistanceField<3>> b = innerDistanceFields<3>(ball, s, 6, false);
    ASSERT_EQ(a.size(), 2u);
    ASSERT_EQ(b.size(), 2u);
    for (std::size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(a[k].values, b[k].values);
        EXPECT_EQ(a[k].sourceNodes, b[k].sourceNodes);
    }
    // Each field is the distance from its own source: 0.4 apart through the ball.
    Real f0, f1;
    ASSERT_TRUE(a[0].sample(s[1], f0));
    ASSERT_TRUE(a[1].sample(s[0], f1));
    EXPECT_NEAR(f0, 0.4, 2 * a[0].h);
    EXPECT_NEAR(f1, 0.4, 2 * a[0].h);
}

TEST(InnerDistance, EmptyWithoutAnInsideNodeAndRefusesBadInput)
{
    // A disc thinner than the lattice: no node inside, no F.
    const Surface<2> speck = circle(Vec<2>(0.51, 0.51), 0.004, 40);
    const InnerDistanceField<2> f = innerDistanceFields<2>(speck, {Vec<2>(0.51, 0.51)}, 4)[0];
    EXPECT_TRUE(f.empty());
    Real v;
    EXPECT_FALSE(f.sample(Vec<2>(0.5, 0.5), v));
    // A source outside the shape seeds the nearest inside node.
    const Surface<2> disc = circle(Vec<2>(0.5, 0.5), 0.2, 300);
    const InnerDistanceField<2> g = innerDistanceFields<2>(disc, {Vec<2>(0.9, 0.5)}, 6)[0];
    ASSERT_EQ(g.sourceNodes, 1u);
    ASSERT_TRUE(g.sample(Vec<2>(0.5, 0.5), v));
    EXPECT_NEAR(v, 0.4, 3 * g.h);
    EXPECT_THROW(innerDistanceFields<2>(disc, {Vec<2>(std::nan(""), 0.5)}, 6), openvdb::ValueError);
    EXPECT_THROW(innerDistanceFields<2>(Surface<2>(), {Vec<2>(0.5, 0.5)}, 6), openvdb::ValueError);
}

TEST(InnerDistance, OwnSourceIsTheNearerEndOfABarOrNoneInItsMiddle)
{
    // A bar 0.6 long and 0.1 wide, a source near each end: inside, F_A(x) ~ x - 0.21 and
    // F_B(x) ~ 0.79 - x along it, so F_B >= 1.5 F_A left of x = (0.79 + 1.5 * 0.21) / 2.5 =
    // 0.442, and F_A >= 1.5 F_B right of 0.558.
    const Surface<2> bar = polygon(
        {Vec<2>(0.2, 0.45), Vec<2>(0.8, 0.45), Vec<2>(0.8, 0.55), Vec<2>(0.2, 0.55)}, 0.005);
    const std::vector<InnerDistanceField<2>> f =
        innerDistanceFields<2>(bar, {Vec<2>(0.21, 0.5), Vec<2>(0.79, 0.5)}, 8);
    ASSERT_EQ(f.size(), 2u);
    Real v;
    for (double y : {0.45, 0.5, 0.55}) { // on both long sides and the axis
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.30, y), 1.5, v), 0) << y;
        EXPECT_NEAR(v, std::hypot(0.30 - 0.21, y - 0.5), 2 * f[0].h);
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.42, y), 1.5, v), 0) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.47, y), 1.5, v), -1) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.50, y), 1.5, v), -1) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.53, y), 1.5, v), -1) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.58, y), 1.5, v), 1) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.70, y), 1.5, v), 1) << y;
        // Ratio 1: every point has the nearer end, the middle included.
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.49, y), 1.0, v), 0) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.51, y), 1.0, v), 1) << y;
        // A larger ratio keeps less of the bar: at x = 0.30, B is 4.8x (the sides) to 5.4x
        // (the axis) as far as A.
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.30, y), 4.0, v), 0) << y;
        EXPECT_EQ(ownSource<2>(f, Vec<2>(0.30, y), 6.0, v), -1) << y;
    }
    // One source: always its own; an empty field is skipped; none at all: -1.
    EXPECT_EQ(ownSource<2>({f[1]}, Vec<2>(0.21, 0.5), 10.0, v), 0);
    const InnerDistanceField<2> none;
    EXPECT_EQ(ownSource<2>({none, f[1]}, Vec<2>(0.3, 0.5), 1.5, v), 1);
    EXPECT_EQ(ownSource<2>({none}, Vec<2>(0.3, 0.5), 1.5, v), -1);
    EXPECT_THROW(ownSource<2>(f, Vec<2>(0.3, 0.5), 0.9, v), openvdb::ValueError);
    EXPECT_THROW(ownSource<2>(f, Vec<2>(0.3, 0.5), std::nan(""), v), openvdb::ValueError);
}
