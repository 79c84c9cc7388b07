/// @file TestConsistency.cc
/// @brief measureConsistency() and its parts: the composition of a sampled analytic map with its
///        sampled analytic inverse converges to Id at second order, composition with the
///        identity is exact, the residual of phi = Id is the distance between the shapes, and
///        det statistics count every Kuhn simplex.
#include "EvalFixture.h"

#include <vdbmatch/eval/Consistency.h>
#include <vdbmatch/eval/ShapeDistance.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <cmath>
#include <support/TestSurfaces.h>

using namespace vdbmatch;
using namespace vdbmatch::test;

namespace {

template <int D>
void
checkSecondOrder(int coarseLevel, int samplesPerCell, double minRatio)
{
    double l2[2], linf[2];
    for (int r = 0; r < 2; ++r) {
        const int level = coarseLevel + r;
        const DeformationField phi = makeField<D>(level, forwardDisplacement<D>);
        const DeformationField psi = makeField<D>(level, inverseDisplacement<D>);
        // The same sample points at both levels (with samplesPerCell > 1 also off the nodes).
        const double spacing =
            WORLD_SCALE * std::ldexp(1.0, -(coarseLevel + 1)) / double(samplesPerCell);
        const eval::DomainError e = eval::compositionErrorOverDomain(phi, psi, spacing);
        EXPECT_GT(e.points, 0u);
        EXPECT_GT(e.linf, 0.0);
        l2[r] = e.l2;
        linf[r] = e.linf;
    }
    // O(h^2): a ratio of about 4 from h to h/2.
    EXPECT_GT(l2[0] / l2[1], minRatio) << l2[0] << " " << l2[1];
    EXPECT_GT(linf[0] / linf[1], minRatio) << linf[0] << " " << linf[1];
    EXPECT_LT(linf[1], 1e-2 * WORLD_SCALE);
}

} // namespace

TEST(Consistency, InverseErrorIsSecondOrder2D)
{
    checkSecondOrder<2>(5, 3, 3.0);
}

TEST(Consistency, InverseErrorIsSecondOrder3D)
{
    // Sampled at the fine nodes, where the fine phi is exact; still pre-asymptotic at these
    // levels (measured L2 ratios 2.40, 2.62, 2.91 for levels 3-4, 4-5, 5-6, tending to 4).
    checkSecondOrder<3>(4, 1, 2.5);
}

TEST(Consistency, CompositionWithIdentityIsExact)
{
    const int level = 5;
    const DeformationField id = makeField<2>(level, zeroDisplacement<2>);
    const DeformationField phi = makeField<2>(level, forwardDisplacement<2>);
    const double h = id.voxelSize();
    const eval::DomainError e0 = eval::compositionErrorOverDomain(id, id, h / 3);
    EXPECT_EQ(e0.linf, 0.0);
    EXPECT_EQ(e0.l2, 0.0);
    // Id o phi - Id = phi - Id: at the nodes (spacing h) its max is the largest node value.
    const eval::DomainError e1 = eval::compositionErrorOverDomain(phi, id, h);
    const eval::DomainError e2 = eval::compositionErrorOverDomain(id, phi, h);
    double largest = 0;
    for (auto it = phi.grid().cbeginValueOn(); it; ++it)
        largest = std::max(largest, double(openvdb::Vec3d(*it).length()));
    EXPECT_NEAR(e1.linf, largest, 1e-12);
    EXPECT_NEAR(e2.linf, largest, 1e-12);
    EXPECT_EQ(e1.points, size_t((1 << level) + 1) * size_t((1 << level) + 1));
}

TEST(Consistency, JacobianStatsCountEverySimplex)
{
    const int level = 3;
    const eval::JacobianStats s3 = eval::jacobianStats(makeField<3>(level, zeroDisplacement<3>));
    EXPECT_EQ(s3.simplices, size_t(6) << (3 * level));
    EXPECT_EQ(s3.min, 1.0);
    EXPECT_EQ(s3.max, 1.0);
    EXPECT_EQ(s3.belowThreshold, 0u);
    const DeformationField phi = makeField<2>(5, forwardDisplacement<2>);
    const eval::JacobianStats s2 = eval::jacobianStats(phi);
    EXPECT_EQ(s2.simplices, size_t(2) << 10);
    EXPECT_LT(s2.min, 1.0);
    EXPECT_GT(s2.max, 1.0);
    EXPECT_GT(s2.min, 0.5);
    // The same values as DeformationField::jacobianDeterminant at sample points.
    for (double t : {0.13, 0.41, 0.77}) {
        const openvdb::Vec3d x = worldOffset(2) + openvdb::Vec3d(t, 1 - t, 0) * WORLD_SCALE;
        const double det = phi.jacobianDeterminant(x);
        EXPECT_GE(det, s2.min);
        EXPECT_LE(det, s2.max);
    }
    // A fold: u pushes a column of nodes past its neighbour.
    const DeformationField fold = makeField<2>(4, [](const Vec<2>& x) {
        Vec<2> u = Vec<2>::Zero();
        if (std::abs(x[0] - 0.5) < 1e-9 && std::abs(x[1] - 0.5) < 1e-9) u[0] = 0.2;
        return u;
    });
    const eval::JacobianStats sf = eval::jacobianStats(fold);
    EXPECT_LT(sf.min, 0.0);
    EXPECT_GT(sf.nonPositive, 0u);
    EXPECT_GE(sf.belowThreshold, sf.nonPositive);
}

TEST(Consistency, ResidualOfIdentityIsTheDistanceBetweenTheShapes)
{
    // Concentric circles, radii 0.25 and 0.3 of Omega (world: times WORLD_SCALE).
    const int vertices = 256;
    const Surface<2> m1 = toWorld(circle(Vec<2>(0.5, 0.5), 0.25, vertices));
    const Surface<2> m2 = toWorld(circle(Vec<2>(0.5, 0.5), 0.3, vertices));
    const DeformationField id = makeField<2>(5, zeroDisplacement<2>);
    const eval::ConsistencyReport r = eval::measureConsistency<2>(id, id, m1, m2);
    EXPECT_FALSE(r.interrupted);
    EXPECT_EQ(r.dim, 2);
    EXPECT_NEAR(r.domainSize, WORLD_SCALE, 1e-12);
    // Distance from a vertex of the inner polygon to the outer polygon: (r2 - r1) cos(pi / n).
    const double expected = WORLD_SCALE * 0.05 * std::cos(M_PI / vertices);
    /// Accuracy of the distance samplers: well below 1e-4 of the domain.
    constexpr double TOLERANCE = 1e-4 * WORLD_SCALE;
    EXPECT_NEAR(r.residualPhi.mean, expected, TOLERANCE);
    EXPECT_NEAR(r.residualPhi.max, expected, TOLERANCE);
    EXPECT_NEAR(r.residualPsi.mean, expected, TOLERANCE);
    EXPECT_NEAR(r.relative(r.residualPhi.mean), 0.05, 1e-4);
    EXPECT_EQ(r.residualPhi.points, size_t(vertices));
    EXPECT_EQ(r.psiPhiDomain.linf, 0.0);
    EXPECT_EQ(r.psiPhiShape.max, 0.0);
    EXPECT_EQ(r.phiPsiShape.max, 0.0);
    EXPECT_EQ(r.detPhi.min, 1.0);
}

TEST(Consistency, MeasuresAnAnalyticPair3D)
{
    const Surface<3> m1 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.25, 12, 24));
    const Surface<3> m2 = toWorld(uvSphere(Vec<3>(0.5, 0.5, 0.5), 0.28, 12, 24));
    const DeformationField phi = makeField<3>(4, forwardDisplacement<3>);
    const DeformationField psi = makeField<3>(4, inverseDisplacement<3>);
    eval::ConsistencyOptions opts;
    opts.distanceLevel = 5;
    const eval::ConsistencyReport r = eval::measureConsistency<3>(phi, psi, m1, m2, opts);
    EXPECT_EQ(r.distanceLevel, 5);
    EXPECT_GT(r.psiPhiDomain.linf, 0.0);
    EXPECT_LT(r.relative(r.psiPhiDomain.linf), 5e-3);
    EXPECT_LT(r.relative(r.phiPsiDomain.linf), 5e-3);
    EXPECT_LE(r.psiPhiShape.max, r.psiPhiDomain.linf * 1.5);
    EXPECT_GT(r.residualPhi.mean, 0.0);
    EXPECT_GT(r.detPhi.min, 0.5);
    EXPECT_EQ(r.detPhi.nonPositive, 0u);
    // Deterministic: the serial run gives the same numbers.
    opts.threaded = false;
    const eval::ConsistencyReport s = eval::measureConsistency<3>(phi, psi, m1, m2, opts);
    EXPECT_EQ(s.psiPhiDomain.l2, r.psiPhiDomain.l2);
    EXPECT_EQ(s.residualPhi.mean, r.residualPhi.mean);
    EXPECT_EQ(s.detPhi.min, r.detPhi.min);
}

TEST(Consistency, RejectsMismatchedInputs)
{
    const DeformationField id2 = makeField<2>(4, zeroDisplacement<2>);
    const DeformationField id3 = makeField<3>(3, zeroDisplacement<3>);
    const Surface<2> inside = toWorld(circle(Vec<2>(0.5, 0.5), 0.25, 64));
    const Surface<2> outside = circle(Vec<2>(10.0, 10.0), 0.25, 64);
    EXPECT_THROW(eval::measureConsistency<2>(id3, id3, inside, inside), openvdb::ValueError);
    EXPECT_THROW(eval::measureConsistency<2>(id2, id2, inside, outside), openvdb::ValueError);
    eval::ConsistencyOptions opts;
    opts.stride = 0;
    EXPECT_THROW(eval::measureConsistency<2>(id2, id2, inside, inside, opts), openvdb::ValueError);
}
