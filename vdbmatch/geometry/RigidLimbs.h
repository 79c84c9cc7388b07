/// @file RigidLimbs.h
/// @brief The moving limbs of an articulation, each carried from M1 to M2 by one rigid motion
///        without a turn about its own axis: points of the limb and their images, for the
///        automatic limb landmarks (an addition to the paper, whose energy has no landmarks;
///        docs/numerics.md "Rigid limbs").
///
/// A round limb looks the same turned about its own axis, so neither d1, d2 nor the stored
/// energies see such a turn, and the coarse levels set it by chance (docs/results.md, "The
/// swung leg turns about its own axis"). The prior here is that a limb swung at a joint moves
/// rigidly, by the least rotation that takes its axis in M1 to its axis in M2 (right for a hinge
/// and for a ball joint that swings; wrong for a forearm's pronation, which no shape term can
/// tell either). For each pair of paired extremities (a in M1, b in M2, Extremities.h) that
/// moved farther than minMotion:
/// 1. g1, g2: the geodesic distance over each surface from its vertex nearest to a (resp. b),
///    by Dijkstra over chords: each vertex joined to the vertices within three edges of it by
///    the straight distance (paths along the edges of a noisy scan add up its zigzag, 1.5x
///    longer on the benchmark's 2D scans, which shrank the scan's limb against the source's);
/// 2. the joint is where the limb meets what stayed: J1, J2 = the least g1, g2 over the still
///    points (the automatic anchors, StillAnchors.h, each taken at its nearest vertex on each
///    shape), and J the smaller (J1 and J2 need not agree: where the shapes coincide changes
///    with the pose, 0.147 and 0.192 on the benchmark's swung leg); the limb is the vertices with g
///    < reach * J, away from the joint, where an articulation bends the skin;
/// 3. the rigid motion (R, t) that best carries M1's limb onto M2's, by trimmed iterative
///    closest points made both ways at once: the pairs are the vertices of M1's limb with their
///    closest vertices of M2 with g2 < targetReach * J, and the vertices of M2's limb with their
///    closest vertices of M1 with g1 < targetReach * J (point to point, weighted by the vertices'
///    shares of the measure, the worst (1 - trim) of all pairs left out; closest points exact,
///    NearestPoints.h), from `starts` rotations: the least rotation between the limbs'
///    principal axes u1, u2, turned about u2 by 360 / starts degrees at a time (the limbs' parts
///    near the tips need not correspond, and a round limb's turn about its axis is anyone's, so
///    the axes alone can start the fit far off). Of the fits that end as close as the closest
///    (within START_TIE = 10% of it or of maxResidual, whichever is larger) the one least
///    turned from the axes is kept: a flattened limb fits as well half a turn about its axis.
///    The fit is the same either way round: from M2 to M1 it gives (R^T, -R^T t) (its starts
///    are the inverses of these). It must fit: the weighted mean distance of the kept pairs at
///    most maxResidual, or the limb is not rigid and is left out;
/// 4. in 3D, R without its turn about the limb's axis u = (u1 + R^T u2) / |...| (both limbs'
///    axes in M1's frame): the least rotation taking u to R u (in 2D there is no such turn: R
///    itself); it turns about the pivot p halfway between M1's limb centroid and where (R, t)
///    takes M2's back, and p goes where (R, t) takes it. Either way round the rotation, the
///    pivot and its image are the same, so the map from M2 to M1 is the inverse of the map
///    from M1 to M2 (to rounding);
/// 5. count / 2 farthest-point samples of each limb (count - count / 2 of M1's), from its vertex
///    nearest the tip: the samples p of M1 paired with their images, those q of M2 with their
///    preimages, so that the match M2 -> M1 holds the same pairs (for an even count) and two
///    independent matches are held to inverse maps; a sample whose partner is off Omega is
///    left out.
/// 6. when a tip stayed (moved by at most segmentMaxTipMotion) but its limb did not (a foot
///    that a squat leaves in place below a bent knee), the segment next to the joint: on each
///    shape, the vertices between segmentFrom and segmentTo of the way from the tip to the
///    joint vertex (the still vertex of least g), measured along the straight line between
///    them, of those nearer this tip than any other (geodesically) and than 1.5 times the
///    shape's own J (a thigh between the knee and the hip). It is fitted as in step 3 with its
///    own vertices as the closest points and held as in steps 4 and 5 (its samples start
///    nearest the tip) when it fits, turned by at least segmentMinAngle degrees (one that
///    barely turned is left to the shape terms and the anchors), and keeps the joint: the map
///    moves the joint vertex of each shape by at most 0.1 J (else the fit found another
///    motion: a band of a limb also fits itself half a turn round). A segment of fewer than
///    minVertices vertices on either shape (a tip next to the still part), or one that turned
///    by less than segmentMinAngle (a limb that stayed), is not reported. On the benchmark's
///    squat (thighs out 22 degrees, shins back in 40) it is the thigh.
/// Limits: a limb stretched or shortened along itself still fits (a cylinder slides along
/// itself), and its points are then held where the rigid motion takes them; a limb bent at a
/// second joint (a knee) does not fit and is left out, as a whole; a flat limb turned about its
/// axis is found at any turn (10, 40 and 70 degrees in the tests; one start alone reaches 10
/// but not 20 degrees); on a round limb every turn fits alike and the least is kept.
/// The result does not depend on the thread count.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/Surface.h>

#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

namespace vdbmatch {

/// Options of findRigidLimbs(); lengths in Omega units.
struct RigidLimbOptions
{
    double minMotion = 0.03;    ///< an extremity moved when |a - b| exceeds this
    double reach = 0.6;         ///< the limb: g < reach * J (0 < reach <= 1)
    double targetReach = 0.8;   ///< the fit's closest points: g < targetReach * J (>= reach)
    double trim = 0.9;          ///< share of the closest pairs the fit keeps (0 < trim <= 1)
    int iterations = 30;        ///< closest-point iterations, >= 1
    int starts = 12;            ///< rotations the fit starts from (turns about the axes), >= 1
    double maxResidual = 0.003; ///< the limb is rigid when the fit's mean distance is at most this

    /// The segment next to the joint (step 6): from <= along < to of the way from the tip to
    /// the joint, 0 <= from < to <= 1; to = 0: not sought.
    double segmentFrom = 0.55, segmentTo = 0.8;
    double segmentMinAngle = 10; ///< a segment is held when turned by at least this, degrees
    /// A segment is sought only for a tip that moved by at most this (Omega units; the anchors'
    /// radius: the tip stayed as the anchors see it), >= 0.
    double segmentMaxTipMotion = 0.03;

    std::size_t count = 20;       ///< samples per limb, both shapes together (>= 2)
    std::size_t minVertices = 20; ///< fewer vertices on either limb: left out
    bool threaded = true;         ///< the closest points use TBB (the result does not depend on it)
};

/// What the fit found of one moving limb (no dimension: MatchResult reports it as it is).
struct RigidLimbFit
{
    std::size_t extremity = 0; ///< index of the pair in the caller's list
    bool segment = false; ///< the segment next to the joint (step 6), not the limb from the tip
    bool used = false;    ///< its samples are in RigidLimbs::source/target
    std::string reason;   ///< why not, when !used
    double sourceJoint = 0, targetJoint = 0;            ///< J1, J2, Omega units
    std::size_t sourceVertices = 0, targetVertices = 0; ///< the limbs' vertices (g < reach J)
    double residual = 0;  ///< the fit's weighted mean distance of the kept pairs
    double angle = 0;     ///< the rotation's angle, degrees (after the axial turn is removed)
    double axialTurn = 0; ///< the turn about the axis the fit had and was removed, degrees
    double joint() const { return std::min(sourceJoint, targetJoint); } ///< J
};

/// One moving limb: the fit and the rigid map it holds.
template <int D> struct RigidLimb : RigidLimbFit
{
    Mat<D> rotation = Mat<D>::Identity();
    Vec<D> sourceCentre = Vec<D>::Zero(), targetCentre = Vec<D>::Zero(); ///< p and its image
    /// The map of the limb: x -> rotation (x - sourceCentre) + targetCentre.
    Vec<D> map(const Vec<D>& x) const { return rotation * (x - sourceCentre) + targetCentre; }
    Vec<D> inverse(const Vec<D>& y) const
    {
        return rotation.transpose() * (y - targetCentre) + sourceCentre;
    }
};

/// The rigid limbs of one pair of shapes.
template <int D> struct RigidLimbs
{
    std::vector<RigidLimb<D>> limbs; ///< one per extremity pair that moved
    /// The samples of the used limbs: source[k] (inside or near M1) goes to target[k].
    std::vector<Vec<D>> source, target;
};

/// The moving limbs of @a unitSource and @a unitTarget (Omega units) that an articulation
/// carried rigidly (see the file comment). @a sourceTips and @a targetTips are the paired
/// extremities (row k of each), @a still the points where the shapes coincide (the anchors).
/// No still point: no limb (the joint cannot be told).
/// @throw openvdb::ValueError if a surface fails checkSurface(), the tip lists differ in size, a
///        point is not finite, or an option is out of its range
template <int D>
RigidLimbs<D>
findRigidLimbs(const Surface<D>& unitSource, const Surface<D>& unitTarget,
               const std::vector<Vec<D>>& sourceTips, const std::vector<Vec<D>>& targetTips,
               const std::vector<Vec<D>>& still, const RigidLimbOptions& opts = RigidLimbOptions());

extern template RigidLimbs<2>
findRigidLimbs<2>(const Surface<2>&, const Surface<2>&, const std::vector<Vec<2>>&,
                  const std::vector<Vec<2>>&, const std::vector<Vec<2>>&, const RigidLimbOptions&);
extern template RigidLimbs<3>
findRigidLimbs<3>(const Surface<3>&, const Surface<3>&, const std::vector<Vec<3>>&,
                  const std::vector<Vec<3>>&, const std::vector<Vec<3>>&, const RigidLimbOptions&);

} // namespace vdbmatch
