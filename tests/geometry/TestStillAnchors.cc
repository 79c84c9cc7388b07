/// @file TestStillAnchors.cc
/// @brief Tests of the still anchors of a pair of shapes (geometry/StillAnchors.h): a square whose
/// target grows a bump on one side is anchored only where both coincide, at least the radius away
/// from the bump, spread over the rest; identical shapes coincide everywhere, shapes a little
/// apart nowhere; the count bounds the anchors; the thread count does not change them.

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/StillAnchors.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

/// The square [0.3, 0.7]^2, counter-clockwise, with n points per side; with @a bump, the middle
/// of its top side, x in [0.45, 0.55], is raised by @a bump (a "limb" that only the target has).
Surface<2>
square(int n, double bump = 0)
{
    Surface<2> s;
    const double lo = 0.3, hi = 0.7;
    auto add = [&](double x, double y) { s.points.emplace_back(x, y); };
    for (int i = 0; i < n; ++i)
        add(lo + (hi - lo) * i / n, lo); // bottom, left to right
    for (int i = 0; i < n; ++i)
        add(hi, lo + (hi - lo) * i / n); // right, upwards
    for (int i = 0; i < n; ++i) {        // top, right to left
        const double x = hi - (hi - lo) * i / n;
        add(x, hi + (bump > 0 && x > 0.45 && x < 0.55 ? bump : 0.0));
    }
    for (int i = 0; i < n; ++i)
        add(lo, hi - (hi - lo) * i / n); // left, downwards
    const int m = int(s.points.size());
    for (int i = 0; i < m; ++i)
        s.elements.push_back({i, (i + 1) % m});
    return s;
}

double
nearestPairDistance(const std::vector<Vec<2>>& p)
{
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = i + 1; j < p.size(); ++j)
            d = std::min(d, (p[i] - p[j]).norm());
    return d;
}

} // namespace

TEST(StillAnchors, OnlyWhereBothCoincideAwayFromWhatMoved)
{
    // The target is sampled independently (another point count): coincidence is a property of
    // the surfaces, not of shared vertices.
    const Surface<2> source = square(100), target = square(77, 0.06);
    StillAnchorOptions opts;
    opts.radius = 0.03;
    opts.count = 40;
    const StillAnchors<2> a = findStillAnchors<2>(source, target, opts);
    ASSERT_EQ(a.points.size(), 40u);
    EXPECT_EQ(a.vertices, source.points.size());
    // The source's top side between x = 0.45 and 0.55 is 0.06 off the target, and it is eroded by
    // the radius: the other vertices (about 400 - 25 - 2 * 7.5) remain, on M2 and coincident.
    EXPECT_NEAR(double(a.onTarget), 400 - 25, 2);
    EXPECT_NEAR(double(a.coincident), 400 - 25 - 15, 3);
    for (const Vec<2>& p : a.points) {
        const bool nearBump = p[1] > 0.69 && p[0] > 0.45 - opts.radius && p[0] < 0.55 + opts.radius;
        EXPECT_FALSE(nearBump) << p.transpose();
    }
    // Spread: 40 samples of a perimeter of about 1.5 lie at least half the even spacing apart.
    EXPECT_GT(nearestPairDistance(a.points), 0.5 * 1.5 / 40);
    // A larger radius erodes more.
    opts.radius = 0.08;
    const StillAnchors<2> wide = findStillAnchors<2>(source, target, opts);
    EXPECT_NEAR(double(wide.coincident), 400 - 25 - 2 * 20, 3);
    for (const Vec<2>& p : wide.points)
        EXPECT_FALSE(p[1] > 0.69 && p[0] > 0.37 && p[0] < 0.63) << p.transpose();
}

TEST(StillAnchors, IdenticalShapesEverywhereShiftedOnesNowhere)
{
    const Surface<2> source = square(100);
    StillAnchorOptions opts;
    opts.count = 1000;
    const StillAnchors<2> same = findStillAnchors<2>(source, square(64), opts);
    EXPECT_EQ(same.coincident, source.points.size());
    EXPECT_DOUBLE_EQ(same.coincidentShare(), 1.0);
    EXPECT_EQ(same.points.size(), source.points.size()); // every vertex, each once
    Surface<2> shifted = square(64);
    for (Vec<2>& p : shifted.points)
        p += Vec<2>(0.01, 0.01);
    const StillAnchors<2> apart = findStillAnchors<2>(source, shifted, opts);
    EXPECT_EQ(apart.coincident, 0u);
    EXPECT_TRUE(apart.points.empty());
    // 3D: a sphere and a finer tessellation of it coincide; a sphere 0.01 larger does not.
    const Surface<3> sphere = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 48, 96);
    const StillAnchors<3> s3 =
        findStillAnchors<3>(sphere, uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 64, 128));
    EXPECT_GT(s3.coincidentShare(), 0.99);
    EXPECT_EQ(s3.points.size(), StillAnchorOptions().count);
    const StillAnchors<3> larger =
        findStillAnchors<3>(sphere, uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.26, 64, 128));
    EXPECT_EQ(larger.coincident, 0u);
}

TEST(StillAnchors, ThreadCountDoesNotMatter)
{
    const Surface<2> source = square(100), target = square(77, 0.06);
    StillAnchorOptions opts;
    opts.count = 25;
    const StillAnchors<2> threaded = findStillAnchors<2>(source, target, opts);
    opts.threaded = false;
    const StillAnchors<2> serial = findStillAnchors<2>(source, target, opts);
    ASSERT_EQ(threaded.points.size(), serial.points.size());
    for (std::size_t k = 0; k < serial.points.size(); ++k)
        EXPECT_EQ(threaded.points[k], serial.points[k]);
}

TEST(StillAnchors, RefusesBadOptions)
{
    const Surface<2> s = square(40);
    StillAnchorOptions opts;
    opts.tolerance = -1;
    EXPECT_THROW(findStillAnchors<2>(s, s, opts), openvdb::ValueError);
    opts.tolerance = 0.002;
    opts.radius = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(findStillAnchors<2>(s, s, opts), openvdb::ValueError);
    EXPECT_THROW(findStillAnchors<2>(Surface<2>(), s), openvdb::ValueError);
}
