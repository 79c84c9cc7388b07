/// @file TestInitialDeformation.cc
/// @brief A deformation grid as the start of a match (--init): a 4..6 result continued at level 7
///        against 4..7 from scratch; refused placements, dimensions and folds; another pair's map
///        carried through world space (--warm-start).
#include "../support/TestSurfaces.h"

#include <vdbmatch/Match.h>
#include <vdbmatch/io/DeformationField.h>
#include <vdbmatch/io/DeformationIO.h>
#include <vdbmatch/io/InitialDeformation.h>

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>

#include <numeric>
#include <string>
#include <type_traits>

using namespace vdbmatch;
using test::ellipseCurve;

namespace {

int
totalIterations(const MatchResult<2>& r)
{
    int n = 0;
    for (const LevelSummary& l : r.levels)
        n += l.report.iterations;
    return n;
}

/// The deformation grid of a result, with the metadata match writes.
openvdb::Vec3SGrid::Ptr
resultGrid(const MatchResult<2>& r, int firstLevel)
{
    openvdb::Vec3SGrid::Ptr grid = makeDeformationGrid<2>(*r.lattice, r.displacement, r.placement);
    grid->insertMeta("vdbmatch_levels",
                     openvdb::StringMetadata(std::to_string(firstLevel) + ".." +
                                             std::to_string(r.lattice->level())));
    grid->insertMeta("vdbmatch_margin", openvdb::DoubleMetadata(r.placement.margin));
    grid->insertMeta("is_interrupted", openvdb::BoolMetadata(r.isInterrupted()));
    return grid;
}

struct InitialDeformationTest : public ::testing::Test
{
    void SetUp() override { openvdb::initialize(); }
    const Surface<2> circle = ellipseCurve(Vec<2>(3.0, -1.0), 2.0, 2.0, 400);
    const Surface<2> ellipse = ellipseCurve(Vec<2>(3.4, -0.8), 2.6, 1.7, 400);
    const UnitBoxPlacement placement = placeInUnitBox<2>(circle, ellipse, DEFAULT_UNIT_BOX_MARGIN);

    /// The 2D defaults at levels first..last.
    static MatchOptions levels(int first, int last)
    {
        MatchOptions opts = MatchOptions::defaults(2);
        opts.multiscale.minLevel = first;
        opts.multiscale.maxLevel = last;
        return opts;
    }
    /// circle -> ellipse at levels first..last.
    MatchResult<2> matched(int first, int last) const
    {
        return match<2>(circle, ellipse, placement, levels(first, last));
    }
};

} // namespace

TEST_F(InitialDeformationTest, ContinuesACoarserResult2D)
{
    MatchOptions opts = levels(4, 7);
    const MatchResult<2> scratch = match<2>(circle, ellipse, placement, opts);
    ASSERT_TRUE(scratch.isComplete());

    opts.multiscale.maxLevel = 6;
    const MatchResult<2> coarse = match<2>(circle, ellipse, placement, opts);
    ASSERT_TRUE(coarse.isComplete());

    const InitialDeformation init =
        initialDeformationFromGrid(resultGrid(coarse, 4), placement, 2, "the 4..6 result");
    EXPECT_EQ(init.gridLevel, 6);
    EXPECT_EQ(init.firstLevel, 4);
    EXPECT_EQ(init.finestLevel, 6);
    EXPECT_FALSE(init.interrupted);
    EXPECT_EQ(init.nextLevel(), 7);
    EXPECT_GE(init.start->lipschitz, 1.0);

    // Level 7 only, from the 4..6 result, with the cells of a run that started at 4.
    opts.multiscale.minLevel = init.nextLevel();
    opts.multiscale.maxLevel = 7;
    opts.coarsestLevel = 4;
    opts.initial = init.start;
    const MatchResult<2> resumed = match<2>(circle, ellipse, placement, opts);
    ASSERT_TRUE(resumed.isComplete());
    ASSERT_EQ(resumed.levels.size(), 1u);
    EXPECT_EQ(resumed.lattice->level(), 7);
    EXPECT_GT(resumed.minJacobian, 0.0);
    // The lattice keeps coarse cells: it is not the dense level-7 lattice.
    EXPECT_LT(resumed.levels[0].lattice.nodes, resumed.levels[0].lattice.denseNodes);
    // It starts where the coarse result ended: its initial energy is far below the identity's.
    EXPECT_LT(resumed.levels[0].report.initialEnergy, scratch.levels[0].report.initialEnergy);

    const double h = std::ldexp(1.0, -7);
    EXPECT_LT(resumed.residual.meanUnit, 1.5 * scratch.residual.meanUnit + 0.05 * h)
        << "resumed " << resumed.residual.meanUnit << ", scratch " << scratch.residual.meanUnit;
    EXPECT_LT(resumed.residual.maxUnit, 0.5 * h);
    const int resumedIterations = totalIterations(resumed);
    const int scratchIterations = totalIterations(scratch);
    EXPECT_LT(resumedIterations, scratchIterations);
    EXPECT_LE(resumedIterations + totalIterations(coarse), scratchIterations + 50);
    std::printf("[ info ] 4..7 from scratch: %d iterations, residual mean %.3e; level 7 from the "
                "4..6 result: %d iterations (+%d for 4..6), residual mean %.3e\n",
                scratchIterations, scratch.residual.meanUnit, resumedIterations,
                totalIterations(coarse), resumed.residual.meanUnit);
}

TEST_F(InitialDeformationTest, ResumesAtTheLastLevel)
{
    // A result as fine as the requested last level: that level runs again from it.
    MatchOptions opts = levels(4, 5);
    const MatchResult<2> first = match<2>(circle, ellipse, placement, opts);
    ASSERT_TRUE(first.isComplete());
    const InitialDeformation init =
        initialDeformationFromGrid(resultGrid(first, 4), placement, 2, "the 4..5 result");
    opts.coarsestLevel = 4;
    opts.multiscale.minLevel = std::min(init.nextLevel(), opts.multiscale.maxLevel);
    EXPECT_EQ(opts.multiscale.minLevel, 5);
    opts.initial = init.start;
    const MatchResult<2> again = match<2>(circle, ellipse, placement, opts);
    ASSERT_TRUE(again.isComplete());
    EXPECT_GT(again.minJacobian, 0.0);
    // Already converged: the resumed level has little left to do.
    EXPECT_LE(again.levels[0].report.energy, first.levels.back().report.energy * (1 + 1e-6));
    EXPECT_LT(again.levels[0].report.iterations, first.levels.back().report.iterations + 5);
}

TEST_F(InitialDeformationTest, RefusesAnotherPlacementOrDimension)
{
    const MatchResult<2> r = matched(3, 4);
    const openvdb::Vec3SGrid::Ptr grid = resultGrid(r, 3);

    const UnitBoxPlacement otherMargin = placeInUnitBox<2>(circle, ellipse, 0.1);
    try {
        initialDeformationFromGrid(grid, otherMargin, 2, "--init 'x.vdb'");
        FAIL() << "expected a placement error";
    } catch (const openvdb::ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("another placement"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("--margin 0.2, this run --margin 0.1"),
                  std::string::npos)
            << e.what();
    }
    const Surface<2> moved = ellipseCurve(Vec<2>(13.0, -1.0), 2.0, 2.0, 400);
    const UnitBoxPlacement otherShapes = placeInUnitBox<2>(moved, ellipse, 0.2);
    EXPECT_THROW(initialDeformationFromGrid(grid, otherShapes, 2, "x"), openvdb::ValueError);
    EXPECT_THROW(initialDeformationFromGrid(grid, placement, 3, "x"), openvdb::ValueError);
    EXPECT_NO_THROW(initialDeformationFromGrid(grid, placement, 2, "x"));
}

TEST_F(InitialDeformationTest, CarriesAnotherPairsMapThroughWorldSpace)
{
    // --warm-start: the grid of one placement read for another (other margin, other shapes):
    // accepted, and u at a point of the new Omega is the world displacement of the old phi at
    // that world point, in the new Omega units; 0 where the world point is outside the old Omega.
    const MatchResult<2> r = matched(3, 5);
    ASSERT_TRUE(r.isComplete());
    const openvdb::Vec3SGrid::Ptr grid = resultGrid(r, 3);
    const DeformationField field(grid);

    const Surface<2> moved = ellipseCurve(Vec<2>(4.5, -0.3), 2.2, 2.0, 400);
    const UnitBoxPlacement other = placeInUnitBox<2>(moved, ellipse, 0.35);
    ASSERT_GT(std::abs(other.scale - placement.scale), 1e-3 * placement.scale);
    EXPECT_THROW(initialDeformationFromGrid(grid, other, 2, "x"), openvdb::ValueError);
    const InitialDeformation init =
        initialDeformationFromGrid(grid, other, 2, "x", InitPlacement::Carried);
    double largest = 0;
    int outside = 0;
    for (int i = 0; i <= 20; ++i) {
        for (int j = 0; j <= 20; ++j) {
            const openvdb::Vec3d xUnit(i / 20.0, j / 20.0, 0.5);
            const openvdb::Vec3d xWorld = other.toWorld(xUnit);
            const openvdb::Vec3d expected = field.displacement(xWorld) * other.scale;
            const openvdb::Vec3d u = init.start->displacement(xUnit);
            EXPECT_NEAR(u[0], expected[0], 1e-12);
            EXPECT_NEAR(u[1], expected[1], 1e-12);
            largest = std::max(largest, std::hypot(u[0], u[1]));
            if (!field.worldBounds().isInside(xWorld)) {
                ++outside;
                EXPECT_EQ(u[0], 0.0);
                EXPECT_EQ(u[1], 0.0);
            }
        }
    }
    EXPECT_GT(largest, 1e-3); // the map moves the circle onto the ellipse
    EXPECT_GT(outside, 0);    // the new Omega reaches beyond the old one
    EXPECT_DOUBLE_EQ(init.start->lipschitz,
                     initialDeformationFromGrid(grid, placement, 2, "x").start->lipschitz);

    // A match of the other pair started from it runs and stays invertible.
    MatchOptions warm = levels(4, 5);
    warm.coarsestLevel = 3;
    warm.initial = init.start;
    const MatchResult<2> w = match<2>(moved, ellipse, other, warm);
    ASSERT_TRUE(w.isComplete());
    EXPECT_EQ(w.levels.front().level, 4);
    EXPECT_GT(w.levels.back().report.minJacobian, 0);
}

TEST_F(InitialDeformationTest, RefusesAFold)
{
    // A grid whose phi mirrors x in the middle of Omega: det D phi < 0 there, so it folds on
    // any lattice it is sampled on.
    const MatchResult<2> r = matched(3, 3);
    NodeVectors<2> u = NodeVectors<2>::Zero(2, Eigen::Index(r.lattice->nodeCount()));
    for (std::size_t i = 0; i < r.lattice->nodeCount(); ++i) {
        const Vec<2> x = r.lattice->nodePosition(i);
        if (std::abs(x[0] - 0.5) < 0.2 && std::abs(x[1] - 0.5) < 0.2)
            u(0, Eigen::Index(i)) = -2 * (x[0] - 0.5);
    }
    const openvdb::Vec3SGrid::Ptr grid = makeDeformationGrid<2>(*r.lattice, u, placement);
    const InitialDeformation init =
        initialDeformationFromGrid(grid, placement, 2, "the folded grid");
    MatchOptions opts = levels(4, 4);
    opts.coarsestLevel = 3;
    opts.initial = init.start;
    try {
        match<2>(circle, ellipse, placement, opts);
        FAIL() << "expected a fold error";
    } catch (const InitialDeformationFolds& e) { // vdb_match --warm-start tells it apart
        static_assert(std::is_base_of_v<openvdb::ValueError, InitialDeformationFolds>);
        EXPECT_NE(std::string(e.what()).find("the folded grid sampled at the nodes of the level 4 "
                                             "lattice folds"),
                  std::string::npos)
            << e.what();
    }
}
