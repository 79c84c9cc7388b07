/// @file TestExtremities.cc
/// @brief Tests of the extremities of a shape (geometry/Extremities.h) and of their pairing
/// between two shapes (geometry/ExtremityMatching.h): a star finds one extremity per arm at the
/// arm's end, a box its two ends; a star turned far is paired by its inner distances, not by
/// nearness; a symmetric star by nearness; different branch counts are refused.

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/Extremities.h>
#include <vdbmatch/geometry/ExtremityMatching.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

const Vec<2> CENTRE(0.5, 0.5);

Surface<2>
star(const std::vector<double>& arms, double inner, double turn)
{
    return starCurve(CENTRE, arms, inner, turn);
}

Vec<2>
armEnd(const std::vector<double>& arms, double turn, std::size_t k)
{
    const double a = turn + 2 * M_PI * double(k) / double(arms.size());
    return CENTRE + arms[k] * Vec<2>(std::cos(a), std::sin(a));
}

/// Each pair (i, j) of @a p joins a's extremity i to b's extremity j at its image by the turn
/// about CENTRE (the extremities of a star turned rigidly turn with it).
void
expectPairedByTurn(const Extremities<2>& a, const Extremities<2>& b, const ExtremityPairing& p,
                   double turn)
{
    const Eigen::Rotation2D<double> rotate(turn);
    for (const auto& [i, j] : p.pairs) {
        const Vec<2> image = CENTRE + rotate * (a.points[i] - CENTRE);
        EXPECT_LT((b.points[j] - image).norm(), 0.03) << "extremity " << i;
    }
}

const std::vector<double> UNEQUAL{0.40, 0.22, 0.34, 0.28, 0.38};
const std::vector<double> EQUAL{0.35, 0.35, 0.35, 0.35, 0.35};
constexpr double INNER = 0.09;

} // namespace

TEST(Extremities, OnePerArmOfAStarAtTheArmsEnd)
{
    const Surface<2> s = star(UNEQUAL, INNER, 0.3);
    const Extremities<2> e = findExtremities<2>(s);
    ASSERT_EQ(e.size(), UNEQUAL.size());
    EXPECT_EQ(e.tips.size(), e.size());
    EXPECT_EQ(e.innerDistance.rows(), Eigen::Index(e.size()));
    for (std::size_t k = 0; k < UNEQUAL.size(); ++k) {
        // The nearest extremity to arm k's end lies on that arm, in its outer part.
        const Vec<2> end = armEnd(UNEQUAL, 0.3, k);
        std::size_t best = 0;
        for (std::size_t i = 1; i < e.size(); ++i)
            if ((e.points[i] - end).norm() < (e.points[best] - end).norm()) best = i;
        const Vec<2> axis = (end - CENTRE).normalized();
        EXPECT_GT((e.points[best] - CENTRE).dot(axis), 0.5 * UNEQUAL[k]) << "arm " << k;
        EXPECT_LT((e.tips[best] - end).norm(), 0.05) << "arm " << k;
    }
    // Most persistent first; inner distances symmetric, positive off the diagonal and at least
    // the straight-line distance between the tips.
    for (std::size_t i = 1; i < e.size(); ++i)
        EXPECT_GE(e.persistence[i - 1], e.persistence[i]);
    for (std::size_t i = 0; i < e.size(); ++i) {
        EXPECT_EQ(e.innerDistance(i, i), 0.0);
        for (std::size_t j = 0; j < e.size(); ++j) {
            EXPECT_EQ(e.innerDistance(i, j), e.innerDistance(j, i));
            if (i != j) {
                EXPECT_GE(e.innerDistance(i, j), (e.tips[i] - e.tips[j]).norm() - 1e-12);
            }
        }
    }
}

TEST(Extremities, TheSameWithAndWithoutThreads)
{
    const Surface<2> s = star(UNEQUAL, INNER, 0.3);
    ExtremityOptions serial;
    serial.threaded = false;
    const Extremities<2> a = findExtremities<2>(s), b = findExtremities<2>(s, serial);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a.points[i], b.points[i]);
        EXPECT_EQ(a.persistence[i], b.persistence[i]);
    }
    EXPECT_EQ(a.innerDistance, b.innerDistance);
}

TEST(Extremities, AnElongatedBoxHasTwoEnds)
{
    // The box [0.2, 0.8] x [0.42, 0.58]^2: its eight corners are maxima of f, but the four at
    // each end meet after a short branch.
    Surface<3> box = cubeMesh(0.0, 1.0);
    for (Vec<3>& p : box.points)
        p = Vec<3>(0.2 + 0.6 * p[0], 0.42 + 0.16 * p[1], 0.42 + 0.16 * p[2]);
    const Extremities<3> e = findExtremities<3>(box);
    ASSERT_EQ(e.size(), 2u);
    EXPECT_LT(std::min(e.points[0][0], e.points[1][0]), 0.35);
    EXPECT_GT(std::max(e.points[0][0], e.points[1][0]), 0.65);
    EXPECT_NEAR(e.innerDistance(0, 1), 0.6, 0.1);
}

TEST(Extremities, BadOptionsAreRefusedAThinShapeHasNone)
{
    ExtremityOptions o;
    o.minPersistence = 0;
    EXPECT_THROW(findExtremities<2>(star(UNEQUAL, INNER, 0), o), openvdb::ValueError);
    o.minPersistence = 0.1;
    o.level = 3; // no lattice node inside a small circle: no extremities, not an error
    const Extremities<2> none = findExtremities<2>(circle(Vec<2>(0.56, 0.56), 0.04, 64), o);
    EXPECT_EQ(none.size(), 0u);
    EXPECT_EQ(none.insideNodes, 0u);
    EXPECT_EQ(none.innerDistance.size(), 0);
}

TEST(ExtremityMatching, AStarTurnedFarIsPairedByInnerDistancesNotByNearness)
{
    // Turned by 100 degrees, each arm end lies nearer to another arm's end of the turned star
    // than to its own image: only the inner distances tell the arms apart.
    const double turn = 100 * M_PI / 180;
    const Extremities<2> a = findExtremities<2>(star(UNEQUAL, INNER, 0.3));
    const Extremities<2> b = findExtremities<2>(star(UNEQUAL, INNER, 0.3 + turn));
    const ExtremityPairing p = matchExtremities<2>(a, b);
    ASSERT_TRUE(p.ok) << p.reason;
    ASSERT_EQ(p.pairs.size(), UNEQUAL.size());
    expectPairedByTurn(a, b, p, turn);
    EXPECT_LT(p.distortion, 0.03);
    // Symmetric: matching back gives the inverse pairing.
    const ExtremityPairing back = matchExtremities<2>(b, a);
    ASSERT_TRUE(back.ok);
    for (const auto& [i, j] : p.pairs)
        EXPECT_EQ(back.pairs[j].second, i);
}

TEST(ExtremityMatching, ASymmetricStarIsPairedByNearness)
{
    // Five equal arms: every rotation of the pairing keeps the inner distances; the pose decides.
    const double turn = 15 * M_PI / 180;
    const Extremities<2> a = findExtremities<2>(star(EQUAL, INNER, 0.1));
    const Extremities<2> b = findExtremities<2>(star(EQUAL, INNER, 0.1 + turn));
    const ExtremityPairing p = matchExtremities<2>(a, b);
    ASSERT_TRUE(p.ok) << p.reason;
    EXPECT_GE(p.candidates, 5u);
    expectPairedByTurn(a, b, p, turn);
}

TEST(ExtremityMatching, DifferentBranchesAreRefused)
{
    const Extremities<2> five = findExtremities<2>(star(UNEQUAL, INNER, 0.3));
    const Extremities<2> four = findExtremities<2>(star({0.4, 0.3, 0.35, 0.25}, INNER, 0.3));
    ASSERT_EQ(four.size(), 4u);
    const ExtremityPairing p = matchExtremities<2>(five, four);
    EXPECT_FALSE(p.ok);
    EXPECT_NE(p.reason.find("5 and 4"), std::string::npos) << p.reason;
    // Same count, other lengths: the inner distances disagree beyond maxDistortion.
    const Extremities<2> other = findExtremities<2>(star({0.40, 0.2, 0.40, 0.2, 0.40}, INNER, 0.3));
    ASSERT_EQ(other.size(), 5u);
    ExtremityMatchOptions strict;
    strict.maxDistortion = 0.05;
    const ExtremityPairing q = matchExtremities<2>(five, other, strict);
    EXPECT_FALSE(q.ok);
    EXPECT_GT(q.leastDistortion, 0.05);
    EXPECT_THROW(matchExtremities<2>(five, five, ExtremityMatchOptions{-1, 0.05}),
                 openvdb::ValueError);
}
