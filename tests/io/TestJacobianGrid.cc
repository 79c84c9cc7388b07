/// @file TestJacobianGrid.cc
/// @brief The volume-ratio grid: phi maps Omega onto itself, so the cell ratios average to 1; its
///        extremes bound the cell values and agree with eval::jacobianStats; the log grid is the
///        logarithm; voxel centres are cell centres.
#include <vdbmatch/eval/Consistency.h>
#include <vdbmatch/io/JacobianGrid.h>

#include <gtest/gtest.h>

#include <cmath>
#include <support/SwirlGrid.h>

using namespace vdbmatch;

TEST(JacobianGrid, VolumeIsPreservedOverOmega)
{
    for (int dim : {2, 3}) {
        // A swirl times a radial stretch: det D phi varies.
        auto grid = test::swirlGrid(dim, 4, 1.0, 0.5);
        for (auto v = grid->beginValueOn(); v; ++v) {
            const openvdb::Coord c = v.getCoord();
            const double x = c.x() / 16.0, y = c.y() / 16.0;
            openvdb::Vec3s w = *v;
            w[0] += float(0.5 * 16 * 0.05 * std::sin(M_PI * x) * std::sin(M_PI * y));
            v.setValue(w);
        }
        const DeformationField phi(grid);
        const openvdb::FloatGrid::Ptr jac = makeJacobianGrid(phi);
        const std::size_t cells = dim == 2 ? 16 * 16 : 16 * 16 * 16;
        ASSERT_EQ(jac->activeVoxelCount(), cells);
        double sum = 0, lo = 1e9, hi = -1e9;
        for (auto v = jac->cbeginValueOn(); v; ++v) {
            sum += *v;
            lo = std::min(lo, double(*v));
            hi = std::max(hi, double(*v));
        }
        EXPECT_NEAR(sum / double(cells), 1.0, 1e-6);
        EXPECT_LT(lo, 0.99);
        EXPECT_GT(hi, 1.01);
        const eval::JacobianStats stats = eval::jacobianStats(phi);
        EXPECT_DOUBLE_EQ(jac->metaValue<double>("vdbmatch_det_min"), stats.min);
        EXPECT_DOUBLE_EQ(jac->metaValue<double>("vdbmatch_det_max"), stats.max);
        EXPECT_LE(stats.min, lo + 1e-6);
        EXPECT_GE(stats.max, hi - 1e-6);
        // Voxel centre = cell centre.
        const openvdb::Vec3d centre = jac->transform().indexToWorld(openvdb::Coord(3, 5, 0));
        const openvdb::Vec3d corner = grid->transform().indexToWorld(openvdb::Coord(3, 5, 0));
        EXPECT_NEAR(centre.x() - corner.x(), 0.25, 1e-12);
        EXPECT_NEAR(centre.y() - corner.y(), 0.25, 1e-12);
        EXPECT_NEAR(centre.z() - corner.z(), dim == 3 ? 0.25 : 0.0, 1e-12);

        const openvdb::FloatGrid::Ptr logJac = makeJacobianGrid(phi, /*logarithm=*/true);
        EXPECT_EQ(logJac->getName(), LOG_JACOBIAN_GRID_NAME);
        auto acc = jac->getConstAccessor();
        for (auto v = logJac->cbeginValueOn(); v; ++v) {
            ASSERT_NEAR(std::exp(double(*v)), acc.getValue(v.getCoord()), 1e-6);
        }
        // Thread count independent.
        const openvdb::FloatGrid::Ptr serial = makeJacobianGrid(phi, false, /*threaded=*/false);
        auto sacc = serial->getConstAccessor();
        for (auto v = jac->cbeginValueOn(); v; ++v) {
            ASSERT_EQ(*v, sacc.getValue(v.getCoord()));
        }
    }
}

TEST(JacobianGrid, LogarithmOfAFoldIsAnError)
{
    auto grid = test::swirlGrid(2, 3, 0.0, 1.0);
    for (auto v = grid->beginValueOn(); v; ++v) {
        v.setValue(openvdb::Vec3s(float(8 - 2 * v.getCoord().x()), 0.0f, 0.0f));
    }
    const DeformationField phi(grid);
    EXPECT_NO_THROW(makeJacobianGrid(phi));
    EXPECT_THROW(makeJacobianGrid(phi, /*logarithm=*/true), openvdb::ValueError);
}
