/// @file TestRigidLimbs.cc
/// @brief Tests of the rigid limbs of an articulation (geometry/RigidLimbs.h): a capsule swung
/// 90 degrees about its base is found rigid, with the swing's angle, and its points go where
/// the swing takes them, either way round (the samples of each shape at the other's
/// preimages), and the fit from M2 to M1 is the inverse of the fit from M1 to M2 on
/// differently sampled, not quite rigid shapes; a turn about the limb's own axis, which a flattened
/// limb lets the fit see, is removed from the map and reported; a limb bent at a second joint is
/// not rigid and is left out; tips that did not move, or no still point, give no limb; the thread
/// count does not change the result; the thigh above a bent knee whose foot stayed (a squat) is
/// held as a segment, and only for a tip that stayed and a segment that turned.

#include "support/TestSurfaces.h"

#include <vdbmatch/geometry/RigidLimbs.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <vector>

using namespace vdbmatch;

namespace {

/// A capsule along z from its south pole at @a base, straight part @a length, radius @a radius
/// (its cross-section's y semi-axis @a flatten times that), rings spaced about evenly in arc
/// length, outward-oriented.
Surface<3>
capsule(const Vec<3>& base, double length, double radius, double flatten = 1.0, int segments = 32)
{
    // The profile (rho, z) from the north pole to the south pole, by arc length.
    const double cap = 0.5 * M_PI * radius, total = 2 * cap + length;
    const int rings = int(std::ceil(total / (2 * M_PI * radius / segments)));
    auto profile = [&](double s, double& rho, double& z) {
        if (s < cap) {
            const double a = s / radius;
            rho = radius * std::sin(a);
            z = length + radius + radius * std::cos(a);
        } else if (s < cap + length) {
            rho = radius;
            z = length + radius - (s - cap);
        } else {
            const double a = (s - cap - length) / radius;
            rho = radius * std::cos(a);
            z = radius - radius * std::sin(a);
        }
    };
    Surface<3> m;
    m.points.push_back(base + Vec<3>(0, 0, length + 2 * radius));
    for (int i = 1; i < rings; ++i) {
        double rho, z;
        profile(total * i / rings, rho, z);
        for (int j = 0; j < segments; ++j) {
            const double phi = 2 * M_PI * j / segments;
            m.points.push_back(base +
                               Vec<3>(rho * std::cos(phi), flatten * rho * std::sin(phi), z));
        }
    }
    m.points.push_back(base);
    const int south = int(m.points.size()) - 1;
    auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    for (int j = 0; j < segments; ++j) {
        m.elements.push_back({0, ring(1, j), ring(1, j + 1)});
        for (int i = 1; i + 1 < rings; ++i) {
            m.elements.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            m.elements.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
        m.elements.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
    }
    return m;
}

Mat<3>
rotationAbout(const Vec<3>& axis, double degrees)
{
    return Eigen::AngleAxis<Real>(degrees * M_PI / 180.0, axis.normalized()).toRotationMatrix();
}

Surface<3>
moved(Surface<3> s, const Mat<3>& R, const Vec<3>& pivot)
{
    for (Vec<3>& p : s.points)
        p = R * (p - pivot) + pivot;
    return s;
}

const Vec<3> BASE(0.3, 0.5, 0.3);
constexpr double LENGTH = 0.3, RADIUS = 0.05;

struct Swing
{
    Surface<3> source, target;
    Mat<3> R;
    std::vector<Vec<3>> sourceTips, targetTips, still;
};

/// The capsule swung by 90 degrees about y through its south pole (the joint, held still),
/// after @a twist degrees about its own axis.
Swing
swing(double flatten, double twist)
{
    Swing s;
    s.source = capsule(BASE, LENGTH, RADIUS, flatten);
    s.R = rotationAbout(Vec<3>::UnitY(), 90.0);
    s.target = moved(moved(s.source, rotationAbout(Vec<3>::UnitZ(), twist), BASE), s.R, BASE);
    const Vec<3> tip = BASE + Vec<3>(0, 0, LENGTH + 2 * RADIUS);
    s.sourceTips = {tip};
    s.targetTips = {s.R * (tip - BASE) + BASE};
    s.still = {BASE};
    return s;
}

} // namespace

TEST(RigidLimbs, SwungCapsuleIsRigidAndGoesWhereTheSwingTakesIt)
{
    const Swing s = swing(1.0, 0.0);
    const RigidLimbs<3> limbs =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still);
    ASSERT_EQ(limbs.limbs.size(), 1u);
    const RigidLimb<3>& l = limbs.limbs[0];
    ASSERT_TRUE(l.used) << l.reason;
    // The joint is the tip's geodesic distance to the still south pole: the capsule's half
    // circumference along a meridian (a little shorter by the chords across the polygonal
    // rings, longer by their zigzag).
    const double meridian = LENGTH + M_PI * RADIUS;
    EXPECT_GT(l.joint(), meridian * 0.99);
    EXPECT_LT(l.joint(), meridian * 1.05);
    EXPECT_NEAR(l.angle, 90.0, 0.5);
    EXPECT_LT(l.residual, 1e-3);
    EXPECT_EQ(limbs.source.size(), RigidLimbOptions().count);
    ASSERT_EQ(limbs.source.size(), limbs.target.size());
    // Every pair is the swing of its source point, the samples of M2 at their preimages too.
    for (std::size_t k = 0; k < limbs.source.size(); ++k) {
        const Vec<3> truth = s.R * (limbs.source[k] - BASE) + BASE;
        EXPECT_LT((limbs.target[k] - truth).norm(), 2e-3) << k;
        // Only the limb, away from the joint: nearer the tip than reach * J.
        EXPECT_LT((limbs.source[k] - s.sourceTips[0]).norm(), RigidLimbOptions().reach * l.joint());
    }
}

TEST(RigidLimbs, TurnAboutTheLimbsAxisIsRemoved)
{
    // A flattened limb turned by 10 degrees about its own axis before the swing: the fit sees
    // the turn, the map keeps only the swing.
    const Swing s = swing(0.5, 10.0);
    const RigidLimbs<3> limbs =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still);
    ASSERT_EQ(limbs.limbs.size(), 1u);
    const RigidLimb<3>& l = limbs.limbs[0];
    ASSERT_TRUE(l.used) << l.reason;
    EXPECT_NEAR(l.axialTurn, 10.0, 2.0);
    EXPECT_NEAR(l.angle, 90.0, 1.0);
    EXPECT_LT((l.rotation - s.R).norm(), 0.03);
}

TEST(RigidLimbs, EitherWayRoundTheMapsAreInverse)
{
    // The target sampled apart from the source (24 segments against 32) and not quite rigid
    // (flattened to 0.96, turned 5 degrees about its axis): the fit is not exact, yet the limb
    // found from M2 to M1 is the inverse of the one from M1 to M2, and both hold the same pairs,
    // so two independent matches are held to inverse maps.
    Swing s = swing(1.0, 0.0);
    s.target = moved(
        moved(capsule(BASE, LENGTH, RADIUS, 0.96, 24), rotationAbout(Vec<3>::UnitZ(), 5.0), BASE),
        s.R, BASE);
    // The closest vertices of the coarser sampling are farther than the default tolerance.
    RigidLimbOptions o;
    o.maxResidual = 0.01;
    const RigidLimbs<3> ab =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still, o);
    const RigidLimbs<3> ba =
        findRigidLimbs<3>(s.target, s.source, s.targetTips, s.sourceTips, s.still, o);
    ASSERT_EQ(ab.limbs.size(), 1u);
    ASSERT_EQ(ba.limbs.size(), 1u);
    const RigidLimb<3>&f = ab.limbs[0], &r = ba.limbs[0];
    ASSERT_TRUE(f.used) << f.reason;
    ASSERT_TRUE(r.used) << r.reason;
    EXPECT_GT(f.residual, 1e-4); // not an exact fit
    EXPECT_NEAR(f.residual, r.residual, 1e-12);
    EXPECT_NEAR(f.angle, r.angle, 1e-9);
    EXPECT_NEAR(f.axialTurn, r.axialTurn, 1e-9);
    EXPECT_LT((f.rotation * r.rotation - Mat<3>::Identity()).norm(), 1e-12);
    for (const Vec<3>& x : s.source.points)
        EXPECT_LT((r.map(f.map(x)) - x).norm(), 1e-12);
    // The same pairs: M1's samples first one way, M2's first the other way.
    ASSERT_EQ(ab.source.size(), ba.source.size());
    const std::size_t n = ab.source.size(), m = RigidLimbOptions().count / 2;
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t j = k < n - m ? k + m : k - (n - m);
        EXPECT_LT((ab.source[k] - ba.target[j]).norm(), 1e-12) << k;
        EXPECT_LT((ab.target[k] - ba.source[j]).norm(), 1e-12) << k;
    }
}

TEST(RigidLimbs, BentLimbIsNotRigid)
{
    // Bent by 45 degrees three quarters along its straight part (a second joint inside the
    // part the fit sees), then swung.
    Swing s = swing(1.0, 0.0);
    Surface<3> bent = s.source;
    const Vec<3> knee = BASE + Vec<3>(0, 0, RADIUS + 0.75 * LENGTH);
    const Mat<3> K = rotationAbout(Vec<3>::UnitY(), 45.0);
    for (Vec<3>& p : bent.points)
        if (p[2] > knee[2]) p = K * (p - knee) + knee;
    s.target = moved(bent, s.R, BASE);
    s.targetTips[0] = s.R * (K * (s.sourceTips[0] - knee) + knee - BASE) + BASE;
    const RigidLimbs<3> limbs =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still);
    ASSERT_EQ(limbs.limbs.size(), 1u);
    EXPECT_FALSE(limbs.limbs[0].used);
    EXPECT_NE(limbs.limbs[0].reason.find("not rigid"), std::string::npos) << limbs.limbs[0].reason;
    EXPECT_GT(limbs.limbs[0].residual, RigidLimbOptions().maxResidual);
    EXPECT_TRUE(limbs.source.empty());
}

TEST(RigidLimbs, StillTipsAndNoStillPointGiveNoLimb)
{
    const Swing s = swing(1.0, 0.0);
    // The tip as its own partner: it did not move.
    EXPECT_TRUE(
        findRigidLimbs<3>(s.source, s.source, s.sourceTips, s.sourceTips, s.still).limbs.empty());
    EXPECT_TRUE(
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, {}).limbs.empty());
}

TEST(RigidLimbs, BadInputThrows)
{
    const Swing s = swing(1.0, 0.0);
    EXPECT_THROW(findRigidLimbs<3>(s.source, s.target, s.sourceTips, {}, s.still),
                 openvdb::ValueError);
    RigidLimbOptions o;
    o.reach = 0.9;
    o.targetReach = 0.8;
    EXPECT_THROW(findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still, o),
                 openvdb::ValueError);
    const std::vector<Vec<3>> nan = {Vec<3>(std::nan(""), 0.5, 0.5)};
    EXPECT_THROW(findRigidLimbs<3>(s.source, s.target, nan, s.targetTips, s.still),
                 openvdb::ValueError);
}

TEST(RigidLimbs, ThreadCountDoesNotChangeTheResult)
{
    const Swing s = swing(0.6, 10.0);
    RigidLimbOptions serial;
    serial.threaded = false;
    const RigidLimbs<3> a =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still);
    const RigidLimbs<3> b =
        findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still, serial);
    ASSERT_EQ(a.source.size(), b.source.size());
    for (std::size_t k = 0; k < a.source.size(); ++k) {
        EXPECT_EQ(a.source[k], b.source[k]);
        EXPECT_EQ(a.target[k], b.target[k]);
    }
}

TEST(RigidLimbs, LargeTurnsAboutTheAxisAreFound)
{
    // A flattened limb turned by 40 and 70 degrees about its own axis before the swing: out of
    // reach of a fit started from the principal axes alone (it is left out as not rigid), found
    // from the other starts, and removed from the map.
    for (double twist : {40.0, 70.0}) {
        const Swing s = swing(0.5, twist);
        const RigidLimbs<3> limbs =
            findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still);
        ASSERT_EQ(limbs.limbs.size(), 1u);
        const RigidLimb<3>& l = limbs.limbs[0];
        ASSERT_TRUE(l.used) << twist << ": " << l.reason;
        EXPECT_NEAR(l.axialTurn, twist, 2.0);
        EXPECT_LT((l.rotation - s.R).norm(), 0.03) << twist;
        RigidLimbOptions one;
        one.starts = 1;
        EXPECT_FALSE(findRigidLimbs<3>(s.source, s.target, s.sourceTips, s.targetTips, s.still, one)
                         .limbs[0]
                         .used)
            << twist;
    }
}

TEST(RigidLimbs, HookedLimbIn2D)
{
    // An arm with its hand bent sideways at the end, swung by 90 degrees about its base, its tip
    // found at the hand's far end on M2 but at the hand's inner corner on M1 (extremities are
    // not corresponding points): the two limbs' parts differ, their principal axes do not turn
    // by the swing, and a fit started from them alone ends near no turn at all and is left out;
    // the other starts find the swing.
    const Vec<2> base(0.45, 0.3);
    const std::vector<Vec<2>> corners = {base + Vec<2>(0.04, 0),     base + Vec<2>(0.04, 0.3),
                                         base + Vec<2>(0.14, 0.3),   base + Vec<2>(0.14, 0.36),
                                         base + Vec<2>(-0.04, 0.36), base + Vec<2>(-0.04, 0)};
    const Surface<2> a = test::polygon(corners, 0.004);
    const double angle = 90 * M_PI / 180;
    Mat<2> R;
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    Surface<2> b = a;
    for (Vec<2>& p : b.points)
        p = R * (p - base) + base;
    const std::vector<Vec<2>> tips1 = {base + Vec<2>(0.10, 0.30)},
                              tips2 = {R * Vec<2>(0.14, 0.33) + base}, still = {base};
    const RigidLimbs<2> limbs = findRigidLimbs<2>(a, b, tips1, tips2, still);
    ASSERT_EQ(limbs.limbs.size(), 1u);
    ASSERT_TRUE(limbs.limbs[0].used) << limbs.limbs[0].reason;
    EXPECT_NEAR(limbs.limbs[0].angle, 90.0, 2.0);
    for (std::size_t k = 0; k < limbs.source.size(); ++k)
        EXPECT_LT((limbs.target[k] - (R * (limbs.source[k] - base) + base)).norm(), 0.01) << k;
    RigidLimbOptions one;
    one.starts = 1;
    const RigidLimb<2> first = findRigidLimbs<2>(a, b, tips1, tips2, still, one).limbs[0];
    EXPECT_FALSE(first.used);
    EXPECT_LT(first.angle, 10.0);
}

TEST(RigidLimbs, SwungStadiumIn2D)
{
    // The 2D outline of the capsule's section (a stadium) swung by 60 degrees about its base.
    Surface<2> a;
    const Vec<2> base(0.3, 0.3);
    const int n = 40;
    for (int i = 0; i < n; ++i) { // right side up, top cap, left side down, bottom cap
        const double t = double(i) / n;
        a.points.push_back(base + Vec<2>(RADIUS, RADIUS + LENGTH * t));
    }
    for (int i = 0; i < n / 2; ++i) {
        const double t = M_PI * i / (n / 2);
        a.points.push_back(base +
                           Vec<2>(RADIUS * std::cos(t), RADIUS + LENGTH + RADIUS * std::sin(t)));
    }
    for (int i = 0; i < n; ++i) {
        const double t = double(i) / n;
        a.points.push_back(base + Vec<2>(-RADIUS, RADIUS + LENGTH * (1 - t)));
    }
    for (int i = 0; i < n / 2; ++i) {
        const double t = M_PI + M_PI * i / (n / 2);
        a.points.push_back(base + Vec<2>(RADIUS * std::cos(t), RADIUS + RADIUS * std::sin(t)));
    }
    const int m = int(a.points.size());
    for (int i = 0; i < m; ++i)
        a.elements.push_back({i, (i + 1) % m});
    const double angle = -60 * M_PI / 180;
    Mat<2> R;
    R << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
    Surface<2> b = a;
    for (Vec<2>& p : b.points)
        p = R * (p - base) + base;
    const Vec<2> tip = base + Vec<2>(0, LENGTH + 2 * RADIUS);
    const RigidLimbs<2> limbs = findRigidLimbs<2>(a, b, {tip}, {R * (tip - base) + base}, {base});
    ASSERT_EQ(limbs.limbs.size(), 1u);
    ASSERT_TRUE(limbs.limbs[0].used) << limbs.limbs[0].reason;
    EXPECT_NEAR(limbs.limbs[0].angle, 60.0, 0.5);
    for (std::size_t k = 0; k < limbs.source.size(); ++k)
        EXPECT_LT((limbs.target[k] - (R * (limbs.source[k] - base) + base)).norm(), 2e-3) << k;
}

namespace {

/// A 2D body with one leg, the leg bent as in a squat: the thigh (hip to knee) turned out by
/// `thigh` degrees about the hip, the shin back by `shin` degrees about the moved knee, so that
/// the foot nearly stays. Returns the two outlines, the foot's tip on each and the still points.
struct Squat
{
    Surface<2> source, target;
    Vec<2> tip1, tip2;
    std::vector<Vec<2>> still;
    Mat<2> thighTurn;
    Vec<2> hip;
};

Mat<2>
turn2(double degrees)
{
    const double a = degrees * M_PI / 180;
    Mat<2> r;
    r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    return r;
}

Squat
squat(double thigh, double shin)
{
    Squat s;
    s.hip = Vec<2>(0.5, 0.6);
    const Vec<2> knee(0.5, 0.4);
    const std::vector<Vec<2>> corners = {Vec<2>(0.46, 0.2), Vec<2>(0.54, 0.2), Vec<2>(0.54, 0.6),
                                         Vec<2>(0.7, 0.6),  Vec<2>(0.7, 0.8),  Vec<2>(0.3, 0.8),
                                         Vec<2>(0.3, 0.6),  Vec<2>(0.46, 0.6)};
    s.source = test::polygon(corners, 0.004);
    s.thighTurn = turn2(thigh);
    const Mat<2> S = turn2(-shin);
    const Vec<2> movedKnee = s.thighTurn * (knee - s.hip) + s.hip;
    const auto pose = [&](const Vec<2>& p) -> Vec<2> {
        if (p[1] >= 0.6 - 1e-9) return p;                              // the body stays
        if (p[1] >= knee[1]) return s.thighTurn * (p - s.hip) + s.hip; // the thigh
        return S * (s.thighTurn * (p - knee)) + movedKnee;             // the shin
    };
    s.target = s.source;
    for (Vec<2>& p : s.target.points)
        p = pose(p);
    s.tip1 = Vec<2>(0.5, 0.2);
    s.tip2 = pose(s.tip1);
    s.still = {Vec<2>(0.44, 0.6), Vec<2>(0.56, 0.6), Vec<2>(0.5, 0.8)};
    return s;
}

} // namespace

TEST(RigidLimbs, SquatHoldsTheThighOfAPlantedFoot)
{
    // Thigh out 20 degrees, shin back 40: the foot moves by 0.024, within the anchors' radius,
    // so the leg is no limb from its tip; the segment next to the hip is the thigh, turned 20
    // degrees about the hip, and its points go where the thigh's turn takes them, up to a
    // slide along the thigh: a straight bar fits itself slid along its axis, and where the
    // band ends on each shape decides the slide (the squat shortens the line from the foot to
    // the hip by 6%, so the bands end 0.01 apart; 2.5 vertex spacings here), and the angle up
    // to the bands' cut: across the line from the tip to the joint on each shape, which the
    // thigh turned against on M2, so that M2's band ends obliquely (1.6 degrees here).
    const Squat s = squat(20, 40);
    ASSERT_LT((s.tip2 - s.tip1).norm(), RigidLimbOptions().segmentMaxTipMotion);
    RigidLimbOptions o;
    o.minMotion = 0.125; // the first band: the foot did not move
    const RigidLimbs<2> limbs =
        findRigidLimbs<2>(s.source, s.target, {s.tip1}, {s.tip2}, s.still, o);
    ASSERT_EQ(limbs.limbs.size(), 1u);
    const RigidLimb<2>& l = limbs.limbs[0];
    EXPECT_TRUE(l.segment);
    ASSERT_TRUE(l.used) << l.reason;
    EXPECT_NEAR(l.angle, 20.0, 2.5);
    EXPECT_LT(l.residual, 2e-3); // 0.0014: inside the 0.003 that being held already implies
    ASSERT_EQ(limbs.source.size(), o.count);
    for (std::size_t k = 0; k < limbs.source.size(); ++k) {
        EXPECT_GT(limbs.source[k][1], 0.4) << k; // on the thigh, above the knee
        EXPECT_LT(limbs.source[k][1], 0.6) << k;
        EXPECT_LT((limbs.target[k] - (s.thighTurn * (limbs.source[k] - s.hip) + s.hip)).norm(),
                  0.015)
            << k;
    }
    // Either way round the same segment, held at the inverse turn.
    const RigidLimbs<2> back =
        findRigidLimbs<2>(s.target, s.source, {s.tip2}, {s.tip1}, s.still, o);
    ASSERT_EQ(back.limbs.size(), 1u);
    ASSERT_TRUE(back.limbs[0].used) << back.limbs[0].reason;
    EXPECT_NEAR(back.limbs[0].angle, l.angle, 1e-6);
}

TEST(RigidLimbs, SegmentsOnlyForATipThatStayedAndALimbThatTurned)
{
    const Squat s = squat(20, 40);
    RigidLimbOptions o;
    o.minMotion = 0.125;
    // The tip moved farther than segmentMaxTipMotion: no segment is sought.
    RigidLimbOptions strict = o;
    strict.segmentMaxTipMotion = 0.01;
    EXPECT_TRUE(
        findRigidLimbs<2>(s.source, s.target, {s.tip1}, {s.tip2}, s.still, strict).limbs.empty());
    // Segments off.
    RigidLimbOptions off = o;
    off.segmentTo = 0;
    EXPECT_TRUE(
        findRigidLimbs<2>(s.source, s.target, {s.tip1}, {s.tip2}, s.still, off).limbs.empty());
    // A thigh turned by less than segmentMinAngle is left to the shape terms, and not reported.
    const Squat small = squat(5, 10);
    EXPECT_TRUE(
        findRigidLimbs<2>(small.source, small.target, {small.tip1}, {small.tip2}, small.still, o)
            .limbs.empty());
    // A band that is no rigid part (from the shin over the knee into the thigh) is refused.
    RigidLimbOptions knee = o;
    knee.segmentFrom = 0.35;
    knee.segmentTo = 0.65;
    const RigidLimbs<2> bent =
        findRigidLimbs<2>(s.source, s.target, {s.tip1}, {s.tip2}, s.still, knee);
    ASSERT_EQ(bent.limbs.size(), 1u);
    EXPECT_FALSE(bent.limbs[0].used);
    EXPECT_TRUE(bent.source.empty());
    // Options out of range.
    RigidLimbOptions bad = o;
    bad.segmentFrom = 0.8;
    bad.segmentTo = 0.7;
    EXPECT_THROW(findRigidLimbs<2>(s.source, s.target, {s.tip1}, {s.tip2}, s.still, bad),
                 openvdb::ValueError);
}
