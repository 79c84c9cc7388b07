/// @file TestSurfacePieces.cc
/// @brief surfacePieces() and smallPieces(): pieces are found through shared vertices, ordered
///        by measure whatever the element order, and a small piece is summed with its share and
///        its distance from the largest.
#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/SurfacePieces.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace vdbmatch;
using vdbmatch::test::addCircle;
using vdbmatch::test::circle;
using vdbmatch::test::cubeMesh;
using vdbmatch::test::uvSphere;

namespace {

/// @a a followed by @a b, b's indices shifted.
Surface<3>
joined(const Surface<3>& a, const Surface<3>& b)
{
    Surface<3> s = a;
    const int32_t shift = int32_t(a.points.size());
    s.points.insert(s.points.end(), b.points.begin(), b.points.end());
    for (auto e : b.elements) {
        for (int32_t& i : e)
            i += shift;
        s.elements.push_back(e);
    }
    return s;
}

} // namespace

TEST(SurfacePieces, OneClosedSurfaceIsOnePiece)
{
    const Surface<3> sphere = uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.3, 12, 24);
    const std::vector<SurfacePiece> p = surfacePieces(sphere);
    ASSERT_EQ(p.size(), 1u);
    EXPECT_EQ(p[0].vertices, sphere.points.size());
    EXPECT_EQ(p[0].elements, sphere.elements.size());
    EXPECT_NEAR(p[0].measure, measure(sphere), 1e-12);
    EXPECT_NEAR(p[0].box.min()[0], 0.2, 1e-12);
    EXPECT_NEAR(p[0].box.max()[2], 0.8, 1e-12);
    const SmallPieces s = smallPieces(sphere);
    EXPECT_EQ(s.pieces, 1u);
    EXPECT_EQ(s.small, 0u);
    EXPECT_EQ(s.smallShare, 0.0);
}

TEST(SurfacePieces, ASmallFragmentIsFoundWithItsShareAndDistance)
{
    // The fragment first in the element order: the largest piece still comes first.
    const Surface<3> big = cubeMesh(0.0, 1.0), fragment = cubeMesh(1.2, 0.05);
    const Surface<3> s = joined(fragment, big);
    const std::vector<SurfacePiece> p = surfacePieces(s);
    ASSERT_EQ(p.size(), 2u);
    EXPECT_NEAR(p[0].measure, 6.0, 1e-12);
    EXPECT_EQ(p[0].first, fragment.elements.size());
    EXPECT_NEAR(p[1].measure, 6 * 0.05 * 0.05, 1e-12);
    EXPECT_EQ(p[1].first, 0u);
    EXPECT_EQ(p[1].vertices, 8u);
    EXPECT_EQ(p[1].elements, 12u);

    const SmallPieces small = smallPieces(s);
    EXPECT_EQ(small.pieces, 2u);
    EXPECT_EQ(small.small, 1u);
    EXPECT_EQ(small.smallVertices, 8u);
    EXPECT_NEAR(small.smallShare, 0.015 / 6.015, 1e-12);
    EXPECT_NEAR(small.farthest, std::sqrt(3.0) * 0.2, 1e-12); // box corner to box corner
    // At a share below the fragment's it is not small.
    EXPECT_EQ(smallPieces(s, 0.001).small, 0u);
}

TEST(SurfacePieces, PiecesOfEqualSizeAreNotSmall)
{
    // The second circle is a little larger: it comes first.
    Surface<2> s = circle(Vec<2>(0.3, 0.5), 0.1, 64);
    addCircle(s, Vec<2>(0.7, 0.5), 0.1001, 64);
    const std::vector<SurfacePiece> p = surfacePieces(s);
    ASSERT_EQ(p.size(), 2u);
    EXPECT_EQ(p[0].first, 64u);
    EXPECT_EQ(p[1].first, 0u);
    EXPECT_EQ(smallPieces(s).small, 0u);
    // An exact tie (the same circle twice) keeps the element order.
    Surface<2> twice = circle(Vec<2>(0.3, 0.5), 0.1, 64);
    addCircle(twice, Vec<2>(0.3, 0.5), 0.1, 64);
    const std::vector<SurfacePiece> q = surfacePieces(twice);
    ASSERT_EQ(q.size(), 2u);
    EXPECT_EQ(q[0].measure, q[1].measure);
    EXPECT_EQ(q[0].first, 0u);
    EXPECT_EQ(q[1].first, 64u);
}

TEST(SurfacePieces, ASmallHoleInsideIsSmallAndNotFar)
{
    // A curve with a small hole: the hole's box lies inside the outline's.
    Surface<2> s = circle(Vec<2>(0.5, 0.5), 0.4, 200);
    addCircle(s, Vec<2>(0.5, 0.5), 0.002, 8, true);
    const SmallPieces small = smallPieces(s);
    EXPECT_EQ(small.pieces, 2u);
    EXPECT_EQ(small.small, 1u);
    EXPECT_EQ(small.farthest, 0.0);
    EXPECT_LT(small.smallShare, 0.01);
}

TEST(SurfacePieces, BadInputThrows)
{
    Surface<3> s = cubeMesh();
    EXPECT_THROW(smallPieces(s, 0.0), openvdb::ValueError);
    EXPECT_THROW(smallPieces(s, 1.0), openvdb::ValueError);
    s.elements[3][1] = 8;
    EXPECT_THROW(surfacePieces(s), openvdb::ValueError);
}
