/// @file TestInverseGrid.cc
/// @brief The inverse grid holds phi^{-1} exactly at its nodes, converges at second order between
///        them, is marked as an inverse, and does not depend on the thread count.
#include <vdbmatch/io/InverseGrid.h>

#include <gtest/gtest.h>

#include <random>
#include <support/SwirlGrid.h>

using namespace vdbmatch;

namespace {

/// Max |psi(phi(x)) - x| over random x, psi the interpolated inverse grid; domain of side 2.
double
interpolatedInverseError(int dim, int level)
{
    const double side = 2.0;
    const DeformationField phi(test::swirlGrid(dim, level, 1.0, side / (1 << level)));
    const InverseGridResult inv = makeInverseGrid(phi);
    EXPECT_EQ(inv.failures, 0u);
    const DeformationField psi(inv.grid);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const openvdb::BBoxd box = phi.worldBounds();
    double worst = 0;
    for (int k = 0; k < 4000; ++k) {
        openvdb::Vec3d x = box.min() + (box.max() - box.min()) *
                                           openvdb::Vec3d(uniform(rng), uniform(rng), uniform(rng));
        if (dim == 2) x[2] = box.min()[2];
        worst = std::max(worst, (psi.apply(phi.apply(x)) - x).length());
    }
    return worst;
}

} // namespace

TEST(InverseGrid, ExactAtTheNodes)
{
    for (int dim : {2, 3}) {
        const DeformationField phi(test::swirlGrid(dim, 4, 1.5, 0.25));
        const InverseGridResult inv = makeInverseGrid(phi);
        ASSERT_TRUE(inv.grid);
        EXPECT_EQ(inv.failures, 0u);
        EXPECT_EQ(inv.nodes, phi.grid().activeVoxelCount());
        EXPECT_EQ(inv.grid->activeVoxelCount(), phi.grid().activeVoxelCount());
        EXPECT_LT(inv.maxResidual, 1e-9);
        // Stored in single precision: phi(y + w(y)) = y up to float rounding of w.
        auto acc = inv.grid->getConstAccessor();
        double worst = 0;
        for (auto v = phi.grid().cbeginValueOn(); v; ++v) {
            const openvdb::Vec3d y = phi.grid().transform().indexToWorld(v.getCoord());
            const openvdb::Vec3d w(acc.getValue(v.getCoord()));
            worst = std::max(worst, (phi.apply(y + w) - y).length());
        }
        EXPECT_LT(worst, 1e-5 * phi.voxelSize());
        EXPECT_EQ(inv.grid->getName(), "displacement");
        EXPECT_EQ(inv.grid->getVectorType(), openvdb::VEC_CONTRAVARIANT_RELATIVE);
        EXPECT_TRUE(inv.grid->metaValue<bool>(INVERSE_METADATA));
        // The inverse of the inverse is marked as a forward map.
        const InverseGridResult back = makeInverseGrid(DeformationField(inv.grid));
        EXPECT_FALSE(back.grid->metaValue<bool>(INVERSE_METADATA));
    }
}

TEST(InverseGrid, InterpolationErrorFallsAtSecondOrder)
{
    for (int dim : {2, 3}) {
        const double e4 = interpolatedInverseError(dim, 4);
        const double e5 = interpolatedInverseError(dim, 5);
        const double e6 = interpolatedInverseError(dim, dim == 2 ? 6 : 5);
        EXPECT_GT(e4 / e5, 3.0) << dim << "D: " << e4 << " " << e5;
        if (dim == 2) {
            EXPECT_GT(e5 / e6, 3.0) << e5 << " " << e6;
        }
    }
}

TEST(InverseGrid, IndependentOfTheThreadCount)
{
    const DeformationField phi(test::swirlGrid(3, 4, 1.5, 0.25));
    const InverseGridResult a = makeInverseGrid(phi, /*threaded=*/true);
    const InverseGridResult b = makeInverseGrid(phi, /*threaded=*/false);
    auto acc = b.grid->getConstAccessor();
    for (auto v = a.grid->cbeginValueOn(); v; ++v) {
        ASSERT_EQ(*v, acc.getValue(v.getCoord()));
    }
}
