/// @file TestDeformationField.cc
/// @brief The deformation grid written by makeDeformationGrid and read back as a
///        DeformationField reproduces the lattice's piecewise-linear phi exactly (up to float
///        storage), on adaptive lattices, in 2D and 3D, and in world units.
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <support/SwirlGrid.h>
#include <vector>

using namespace vdbmatch;

namespace {

template <int D>
void
checkRoundTrip()
{
    // Refined near a circle/sphere, coarse elsewhere: hanging nodes and cells of 3 sizes.
    const RefinementPredicate<D> nearSphere = [](const Vec<D>& c, Real r) {
        return std::abs((c - Vec<D>::Constant(0.5)).norm() - 0.25) < 0.05 + r;
    };
    const SimplexLattice<D> lattice = buildAdaptiveLattice<D>(D == 2 ? 6 : 5, 2, nearSphere);
    ASSERT_GT(lattice.hangingNodeCount(), 0u);
    // A smooth displacement vanishing on the boundary, constrained to the lattice's P1 space.
    NodeVectors<D> u(D, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        const Vec<D> x = lattice.nodePosition(i);
        Real bump = 1;
        for (int a = 0; a < D; ++a)
            bump *= std::sin(M_PI * x[a]);
        for (int a = 0; a < D; ++a)
            u(a, Eigen::Index(i)) = 0.03 * bump * std::cos(3 * x[a] + a);
    }
    lattice.expand(u);

    UnitBoxPlacement placement;
    placement.scale = 0.25;
    placement.worldOrigin = openvdb::Vec3d(-1.0, 2.0, 0.5);
    const openvdb::Vec3SGrid::Ptr grid = makeDeformationGrid<D>(lattice, u, placement);
    const DeformationField field(grid);
    EXPECT_EQ(field.dimension(), D);
    EXPECT_NEAR(field.voxelSize(), lattice.h() / placement.scale, 1e-12);

    const multiscale::PiecewiseLinearInterpolator<D> phi(lattice);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    double worst = 0, worstDet = 0;
    for (int k = 0; k < 2000; ++k) {
        Vec<D> x;
        for (int a = 0; a < D; ++a)
            x[a] = uniform(rng);
        Vec<D> du;
        ASSERT_TRUE(phi.evaluate(u, x, du));
        openvdb::Vec3d unit(0.5);
        for (int a = 0; a < D; ++a)
            unit[a] = x[a];
        const openvdb::Vec3d world = placement.toWorld(unit);
        const openvdb::Vec3d got = field.displacement(world);
        for (int a = 0; a < D; ++a) {
            worst = std::max(worst, std::abs(got[a] - du[a] / placement.scale));
        }
        // det D phi is scale invariant: compare with the lattice's simplex via differences.
        const double det = field.jacobianDeterminant(world);
        EXPECT_GT(det, 0.0);
        worstDet = std::max(worstDet, std::abs(det - 1.0));
    }
    // Float storage of values of size ~0.1 world: about 1e-8.
    EXPECT_LT(worst, 1e-6);
    EXPECT_GT(worstDet, 1e-3); // the map is not the identity
    // Outside the domain phi = Id.
    EXPECT_EQ(field.displacement(placement.toWorld(openvdb::Vec3d(1.5, 0.5, 0.5))),
              openvdb::Vec3d(0.0));

    // The exact inverse, at random points and at points of the lattice's coarse cells, on their
    // faces and next to hanging nodes (nodes of the finest grid: faces of every voxel simplex).
    const double tol = 1e-5 * field.voxelSize();
    double worstInverse = 0;
    auto checkInverse = [&](const Vec<D>& x) {
        openvdb::Vec3d unit(0.5);
        for (int a = 0; a < D; ++a)
            unit[a] = x[a];
        const openvdb::Vec3d world = placement.toWorld(unit);
        const DeformationField::InverseResult back = field.inverse(field.apply(world));
        ASSERT_TRUE(back.found);
        worstInverse = std::max(worstInverse, (back.x - world).length());
        const DeformationField::InverseResult pre = field.inverse(world);
        ASSERT_TRUE(pre.found);
        worstInverse = std::max(worstInverse, (field.apply(pre.x) - world).length());
    };
    for (int k = 0; k < 2000; ++k) {
        Vec<D> x;
        for (int a = 0; a < D; ++a)
            x[a] = uniform(rng);
        checkInverse(x);
    }
    for (std::size_t i = 0; i < lattice.nodeCount(); i += 7) {
        checkInverse(lattice.nodePosition(i));
    }
    EXPECT_LT(worstInverse, tol);
}

/// Every voxel of the dense grid is the interpolator's value at its node, to the last bit, on a
/// lattice with cells up to 8 voxels wide (whole leaves inside one cell, their lower faces next
/// to finer, equal and coarser cells, and the boundary of Omega), even for a discontinuous
/// field.
template <int D>
void
checkEveryNodeIsTheSearch()
{
    const int level = D == 2 ? 8 : 6;
    const RefinementPredicate<D> nearSphere = [](const Vec<D>& c, Real r) {
        return std::abs((c - Vec<D>::Constant(0.45)).norm() - 0.2) < 0.02 + r;
    };
    const SimplexLattice<D> lattice = buildAdaptiveLattice<D>(level, 3, nearSphere);
    NodeVectors<D> u(D, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        const Vec<D> x = lattice.nodePosition(i);
        for (int a = 0; a < D; ++a)
            u(a, Eigen::Index(i)) = lattice.isBoundaryNode(i) ? 0.0 : 0.01 * std::sin(7 * x[a] + a);
    }
    // Hanging values off their constraints (as a field that is not continuous): then the value
    // at a node on a face depends on which cell is used, and the grid must use the cell that
    // the interpolator's search finds.
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        if (lattice.isHangingNode(i)) u(0, Eigen::Index(i)) += 1e-3;
    const openvdb::Vec3SGrid::Ptr grid = makeDeformationGrid<D>(lattice, u, UnitBoxPlacement());
    const multiscale::PiecewiseLinearInterpolator<D> phi(lattice);
    const double h = lattice.h();
    std::size_t nodes = 0, different = 0;
    for (auto v = grid->cbeginValueOn(); v; ++v) {
        Vec<D> x, du;
        for (int a = 0; a < D; ++a)
            x[a] = v.getCoord()[a] * h;
        ASSERT_TRUE(phi.evaluate(u, x, du));
        for (int a = 0; a < D; ++a)
            if (v.getValue()[a] != float(du[a])) ++different;
        ++nodes;
    }
    EXPECT_EQ(nodes, std::size_t(std::pow((1 << level) + 1, D)));
    EXPECT_EQ(different, 0u);
}

} // namespace

TEST(DeformationField, EveryNodeIsTheInterpolatorsValue2D)
{
    checkEveryNodeIsTheSearch<2>();
}
TEST(DeformationField, EveryNodeIsTheInterpolatorsValue3D)
{
    checkEveryNodeIsTheSearch<3>();
}

TEST(DeformationField, ReproducesAdaptiveLatticeMap2D)
{
    checkRoundTrip<2>();
}
TEST(DeformationField, ReproducesAdaptiveLatticeMap3D)
{
    checkRoundTrip<3>();
}

namespace {

void
checkSwirlInverse(int dim)
{
    const double voxel = 0.1;
    const DeformationField field(test::swirlGrid(dim, 5, 1.5, voxel));
    ASSERT_EQ(field.dimension(), dim);
    const openvdb::BBoxd box = field.worldBounds();
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    double worst = 0;
    int longestWalk = 0;
    std::vector<openvdb::Vec3d> points;
    DeformationField::Cursor cursor(field);
    for (int k = 0; k < 3000; ++k) {
        openvdb::Vec3d y = box.min() + (box.max() - box.min()) *
                                           openvdb::Vec3d(uniform(rng), uniform(rng), uniform(rng));
        if (dim == 2) y[2] = box.min()[2];
        points.push_back(y);
        const DeformationField::InverseResult r = field.inverse(y);
        ASSERT_TRUE(r.found);
        longestWalk = std::max(longestWalk, r.simplices);
        worst = std::max(worst, (field.apply(r.x) - y).length());
        // The walk's own residual (its last simplex's affine map) is rounding too.
        EXPECT_LT(r.residual, 1e-9 * voxel);
        // A cursor (one accessor kept between queries) gives the same bits.
        const DeformationField::InverseResult c = cursor.inverse(y);
        EXPECT_EQ(c.x, r.x);
        EXPECT_EQ(c.simplices, r.simplices);
        EXPECT_EQ(cursor.apply(y), field.apply(y));
        worst = std::max(worst, (field.inverse(field.apply(y)).x - y).length());
    }
    EXPECT_LT(worst, 1e-5 * voxel);
    EXPECT_GT(longestWalk, 5); // the walk, not the initial guess, found these

    // Outside Omega phi^{-1} = Id; in parallel and serially, the same bits.
    const openvdb::Vec3d outside = box.max() + openvdb::Vec3d(1.0, 0.5, dim == 3 ? 0.25 : 0.0);
    EXPECT_EQ(field.inverse(outside).x, outside);
    std::vector<openvdb::Vec3d> serial = points, parallel = points;
    EXPECT_EQ(field.mapPoints(serial, /*inverse=*/true, /*threaded=*/false), 0u);
    EXPECT_EQ(field.mapPoints(parallel, /*inverse=*/true, /*threaded=*/true), 0u);
    EXPECT_EQ(serial, parallel);
    EXPECT_EQ(field.mapPoints(parallel, /*inverse=*/false), 0u);
    for (std::size_t i = 0; i < points.size(); ++i) {
        EXPECT_LT((parallel[i] - points[i]).length(), 1e-5 * voxel);
    }
}

} // namespace

TEST(DeformationField, ExactInverseOfASwirl2D)
{
    checkSwirlInverse(2);
}
TEST(DeformationField, ExactInverseOfASwirl3D)
{
    checkSwirlInverse(3);
}

TEST(DeformationField, InverseOfTheIdentityIsTheIdentity)
{
    const DeformationField field(test::swirlGrid(3, 3, 0.0, 0.5));
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> uniform(-1.0, 6.0);
    for (int k = 0; k < 200; ++k) {
        const openvdb::Vec3d y(uniform(rng), uniform(rng), uniform(rng));
        const DeformationField::InverseResult r = field.inverse(y);
        EXPECT_TRUE(r.found);
        EXPECT_EQ(r.x, y);
        EXPECT_EQ(r.simplices, 1);
    }
}

TEST(DeformationField, InverseReportsAFoldInsteadOfLooping)
{
    // A mirror image of the domain (phi_x(i) = n - i): every simplex inside is inverted.
    auto grid = test::swirlGrid(2, 3, 0.0, 1.0);
    for (auto v = grid->beginValueOn(); v; ++v) {
        v.setValue(openvdb::Vec3s(float(8 - 2 * v.getCoord().x()), 0.0f, 0.0f));
    }
    const DeformationField field(grid);
    EXPECT_LT(field.jacobianDeterminant(openvdb::Vec3d(4.5, 4.2, 0.0)), 0.0);
    // (The simplices between the last node and the identity beyond the grid are not inverted:
    // a walk may end there at a true preimage. What is asserted: no hang, no false claim.)
    int failures = 0;
    for (int i = 0; i < 8; ++i) {
        for (int j = 0; j < 8; ++j) {
            const openvdb::Vec3d y(i + 0.3, j + 0.6, 0.0);
            const DeformationField::InverseResult r = field.inverse(y);
            EXPECT_TRUE(std::isfinite(r.x.length()));
            if (r.found) {
                EXPECT_LT((field.apply(r.x) - y).length(), 1e-9);
            } else {
                ++failures;
            }
        }
    }
    EXPECT_GT(failures, 16);
}

TEST(DeformationField, JacobianMatchesFiniteDifferences)
{
    const DeformationField field(test::swirlGrid(3, 4, 1.0, 0.25));
    const openvdb::Vec3d x = field.worldBounds().getCenter() + openvdb::Vec3d(0.113, 0.071, 0.19);
    const openvdb::Mat3d J = field.jacobian(x);
    const double eps = 1e-4 * field.voxelSize();
    for (int c = 0; c < 3; ++c) {
        openvdb::Vec3d e(0.0);
        e[c] = eps;
        // x is inside one simplex: phi is affine on a neighbourhood.
        const openvdb::Vec3d column = (field.apply(x + e) - field.apply(x - e)) / (2 * eps);
        for (int r = 0; r < 3; ++r)
            EXPECT_NEAR(J(r, c), column[r], 1e-6);
    }
    EXPECT_NEAR(field.jacobianDeterminant(x), J.det(), 1e-12);
}

TEST(DeformationField, InverseReportsTheInverseJacobian)
{
    // J of an inverse is (D phi)^{-1} on the simplex where the walk ended: at phi^{-1}(y).
    for (int dim : {2, 3}) {
        const DeformationField field(test::swirlGrid(dim, 4, 1.0, 0.25));
        const openvdb::BBoxd box = field.worldBounds();
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> uniform(0.2, 0.8);
        for (int k = 0; k < 100; ++k) {
            openvdb::Vec3d y = box.min();
            for (int a = 0; a < dim; ++a)
                y[a] += uniform(rng) * box.extents()[a];
            const DeformationField::InverseResult r = field.inverse(y);
            ASSERT_TRUE(r.found);
            const openvdb::Mat3d product = r.jacobian * field.jacobian(r.x);
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    EXPECT_NEAR(product(i, j), i == j ? 1.0 : 0.0, 1e-9) << dim << "D";
        }
    }
}

TEST(DeformationField, CellDeterminantsAreTheSixKuhnSimplices)
{
    // det D phi on the Kuhn simplices of a unit cell, in the order of std::next_permutation of
    // the axes (the path 0 -> e_o0 -> e_o0 + e_o1 -> 1), computed independently with Eigen.
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uniform(-0.3, 0.3);
    for (int trial = 0; trial < 50; ++trial) {
        openvdb::Vec3d u[8];
        for (auto& c : u)
            c = openvdb::Vec3d(uniform(rng), uniform(rng), uniform(rng));
        double dets[6];
        ASSERT_EQ(DeformationField::cellDeterminants(3, u, dets), 6);
        std::array<int, 3> order{{0, 1, 2}};
        int k = 0;
        do {
            Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
            int mask = 0;
            for (int m = 0; m < 3; ++m) {
                const int next = mask | (1 << order[m]);
                for (int r = 0; r < 3; ++r)
                    A(r, order[m]) += u[next][r] - u[mask][r];
                mask = next;
            }
            EXPECT_NEAR(dets[k++], A.determinant(), 1e-14);
        } while (std::next_permutation(order.begin(), order.end()));
    }
    // An affine displacement u(c) = M c: every simplex has det(1 + M).
    Eigen::Matrix3d M;
    M << 0.1, -0.2, 0.05, 0.3, 0.0, -0.1, 0.02, 0.15, -0.25;
    openvdb::Vec3d u[8];
    for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d v = M * Eigen::Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        u[c] = openvdb::Vec3d(v[0], v[1], v[2]);
    }
    double dets[6];
    DeformationField::cellDeterminants(3, u, dets);
    for (double d : dets)
        EXPECT_NEAR(d, (Eigen::Matrix3d::Identity() + M).determinant(), 1e-14);
}

TEST(DeformationField, RejectsRotatedTransforms)
{
    auto grid = openvdb::Vec3SGrid::create();
    grid->tree().setValueOn(openvdb::Coord(0, 0, 0), openvdb::Vec3s(0.0f));
    auto xform = openvdb::math::Transform::createLinearTransform(0.5);
    xform->postRotate(0.3, openvdb::math::Z_AXIS);
    grid->setTransform(xform);
    EXPECT_THROW(DeformationField{grid}, openvdb::ValueError);
    EXPECT_THROW(DeformationField{openvdb::Vec3SGrid::create()}, openvdb::ValueError);
}
