/// @file TestDeformationField.cc
/// @brief The deformation grid written by makeDeformationGrid and read back as a
///        DeformationField reproduces the lattice's piecewise-linear phi exactly (up to float
///        storage), on adaptive lattices, in 2D and 3D, and in world units.
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

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
}

} // namespace

TEST(DeformationField, ReproducesAdaptiveLatticeMap2D)
{
    checkRoundTrip<2>();
}
TEST(DeformationField, ReproducesAdaptiveLatticeMap3D)
{
    checkRoundTrip<3>();
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
