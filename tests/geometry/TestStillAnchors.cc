/// @file TestStillAnchors.cc
/// @brief Tests of the still anchors of a pair of shapes (geometry/StillAnchors.h): a square whose
/// target grows a bump on one side is anchored only where both coincide, at least the radius away
/// from the bump, spread over the rest; the anchors are the same whichever shape is the source;
/// identical shapes coincide everywhere, shapes a little apart nowhere; the count bounds the
/// anchors; the thread count does not change them.

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
    // The target's vertices against the source: its 20 raised ones are off; they lie 0.06 above
    // the others, beyond the radius, so the erosion takes no more.
    EXPECT_EQ(a.targetVertices, target.points.size());
    EXPECT_NEAR(double(a.targetCoincident), 308 - 20, 2);
    // Every anchor is a coincident vertex of one of the shapes: at least the radius from the
    // vertices of that shape that are off the other (the source's under the bump, the target's
    // raised ones).
    const auto farFromWhatMoved = [&](const Vec<2>& p, double r) {
        const auto isVertexOf = [&](const Surface<2>& s) {
            return std::find(s.points.begin(), s.points.end(), p) != s.points.end();
        };
        const auto farFrom = [&](const Surface<2>& s, auto off) {
            for (const Vec<2>& q : s.points)
                if (off(q) && (q - p).norm() < r) return false;
            return true;
        };
        const bool sourceOk = isVertexOf(source) && farFrom(source, [](const Vec<2>& q) {
                                  return q[1] > 0.69 && q[0] > 0.45 && q[0] < 0.55;
                              });
        const bool targetOk =
            isVertexOf(target) && farFrom(target, [](const Vec<2>& q) { return q[1] > 0.71; });
        return sourceOk || targetOk;
    };
    for (const Vec<2>& p : a.points)
        EXPECT_TRUE(farFromWhatMoved(p, opts.radius)) << p.transpose();
    // Spread: 40 samples of a perimeter of about 1.5 lie at least half the even spacing apart.
    EXPECT_GT(nearestPairDistance(a.points), 0.5 * 1.5 / 40);
    // A larger radius erodes more.
    opts.radius = 0.08;
    const StillAnchors<2> wide = findStillAnchors<2>(source, target, opts);
    EXPECT_NEAR(double(wide.coincident), 400 - 25 - 2 * 20, 3);
    EXPECT_LT(wide.targetCoincident, a.targetCoincident);
    for (const Vec<2>& p : wide.points)
        EXPECT_TRUE(farFromWhatMoved(p, opts.radius)) << p.transpose();
}

TEST(StillAnchors, TheSameEitherWayRound)
{
    // The match M2 -> M1 must hold the very points that M1 -> M2 holds, or two independent runs
    // drift apart there (|psi o phi - Id|).
    const Surface<2> source = square(100), target = square(77, 0.06);
    StillAnchorOptions opts;
    opts.count = 40;
    const StillAnchors<2> ab = findStillAnchors<2>(source, target, opts);
    const StillAnchors<2> ba = findStillAnchors<2>(target, source, opts);
    ASSERT_EQ(ab.points.size(), 40u);
    ASSERT_EQ(ab.points.size(), ba.points.size());
    for (std::size_t k = 0; k < ab.points.size(); ++k)
        EXPECT_EQ(ab.points[k], ba.points[k]) << k;
    EXPECT_EQ(ab.onTarget, ba.targetOnSource);
    EXPECT_EQ(ab.targetOnSource, ba.onTarget);
    EXPECT_EQ(ab.coincident, ba.targetCoincident);
    EXPECT_EQ(ab.targetCoincident, ba.coincident);
    EXPECT_DOUBLE_EQ(ab.coincidentShare(), ba.coincidentShare());
    // Both shapes' vertices are candidates: some anchors are the target's own.
    const auto isVertexOf = [](const Surface<2>& s, const Vec<2>& p) {
        return std::find(s.points.begin(), s.points.end(), p) != s.points.end();
    };
    EXPECT_TRUE(std::any_of(ab.points.begin(), ab.points.end(),
                            [&](const Vec<2>& p) { return !isVertexOf(source, p); }));
    EXPECT_TRUE(std::any_of(ab.points.begin(), ab.points.end(),
                            [&](const Vec<2>& p) { return !isVertexOf(target, p); }));

    // 3D: a sphere against a finer tessellation of itself with a dent.
    const Surface<3> s1 = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 24, 48);
    Surface<3> s2 = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 32, 64);
    for (Vec<3>& p : s2.points)
        if (p[2] > 0.7) p[2] = 0.7;
    const StillAnchors<3> ab3 = findStillAnchors<3>(s1, s2), ba3 = findStillAnchors<3>(s2, s1);
    ASSERT_EQ(ab3.points.size(), ba3.points.size());
    ASSERT_GT(ab3.points.size(), 0u);
    for (std::size_t k = 0; k < ab3.points.size(); ++k)
        EXPECT_EQ(ab3.points[k], ba3.points[k]) << k;
    for (const Vec<3>& p : ab3.points)
        EXPECT_LT(p[2], 0.7 - 0.5 * StillAnchorOptions().radius) << p.transpose();
}

TEST(StillAnchors, IdenticalShapesEverywhereShiftedOnesNowhere)
{
    const Surface<2> source = square(100);
    StillAnchorOptions opts;
    opts.count = 1000;
    const StillAnchors<2> same = findStillAnchors<2>(source, square(64), opts);
    EXPECT_EQ(same.coincident, source.points.size());
    EXPECT_DOUBLE_EQ(same.coincidentShare(), 1.0);
    // Every vertex of both, each once (the squares share some).
    std::vector<Vec<2>> both = source.points;
    for (const Vec<2>& p : square(64).points)
        if (std::find(source.points.begin(), source.points.end(), p) == source.points.end())
            both.push_back(p);
    EXPECT_EQ(same.points.size(), both.size());
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
