/// @file TestSimplexLattice.cc
/// @brief Kuhn split: simplices tile each cell, linear fields are reproduced exactly, the split is
///        nested under refinement; node numbering, Dirichlet nodes, slot gathering, grid I/O.
#include <vdbmatch/lattice/SimplexLattice.h>

#include <gtest/gtest.h>

#include <random>

using namespace vdbmatch;

namespace {

template <int D>
void
checkKuhnTiling()
{
    const auto& paths = KuhnSplit<D>::path();
    const auto& axes = KuhnSplit<D>::axis();
    // Volumes: each simplex of the unit cube has volume 1/d!, together 1.
    Real total = 0;
    for (std::size_t p = 0; p < paths.size(); ++p) {
        Mat<D> E;
        for (int m = 1; m <= D; ++m) {
            EXPECT_EQ(paths[p][m] ^ paths[p][m - 1], 1 << axes[p][m]);
            for (int a = 0; a < D; ++a)
                E(a, m - 1) = ((paths[p][m] >> a) & 1) - ((paths[p][0] >> a) & 1);
        }
        EXPECT_EQ(paths[p][0], 0);
        EXPECT_EQ(paths[p][D], (1 << D) - 1); // main diagonal shared by all simplices
        total += std::abs(E.determinant());
        EXPECT_NEAR(std::abs(E.determinant()), 1.0, 1e-15);
    }
    EXPECT_NEAR(total / (D == 2 ? 2 : 6), 1.0, 1e-15);
    // Random points in the cube: exactly one simplex contains each (interior) point.
    std::mt19937 rng(1);
    std::uniform_real_distribution<Real> U(0, 1);
    for (int trial = 0; trial < 1000; ++trial) {
        Vec<D> x;
        for (int a = 0; a < D; ++a)
            x[a] = U(rng);
        int containing = 0;
        for (std::size_t p = 0; p < paths.size(); ++p) {
            // simplex p = {x : x_{pi(1)} >= x_{pi(2)} >= ... }
            bool in = true;
            for (int m = 1; m < D; ++m)
                in = in && x[axes[p][m]] >= x[axes[p][m + 1]];
            containing += in;
        }
        EXPECT_EQ(containing, 1);
    }
}

} // namespace

TEST(SimplexLattice, KuhnTiling2D)
{
    checkKuhnTiling<2>();
}
TEST(SimplexLattice, KuhnTiling3D)
{
    checkKuhnTiling<3>();
}

TEST(SimplexLattice, DenseCountsAndBoundary)
{
    const auto L = SimplexLattice<3>::dense(3);
    EXPECT_EQ(L.cellCount(), 512u);
    EXPECT_EQ(L.nodeCount(), 729u);
    EXPECT_EQ(L.simplexCount(), 512u * 6);
    std::size_t boundary = 0;
    for (std::size_t i = 0; i < L.nodeCount(); ++i) {
        boundary += L.isBoundaryNode(i);
        EXPECT_EQ(L.findNode(L.nodeCoord(i)), int32_t(i));
    }
    EXPECT_EQ(boundary, 729u - 343u);
    const auto L2 = SimplexLattice<2>::dense(4);
    EXPECT_EQ(L2.cellCount(), 256u);
    EXPECT_EQ(L2.nodeCount(), 289u);
    for (std::size_t i = 0; i < L2.nodeCount(); ++i)
        EXPECT_EQ(L2.nodeCoord(i).z(), 0);
}

TEST(SimplexLattice, GatherSumsEverySlotOnce)
{
    const auto L =
        SimplexLattice<3>::box(4, openvdb::CoordBBox(openvdb::Coord(2), openvdb::Coord(12)));
    // Put 1 in every slot: the gathered value is the number of blocks touching the node.
    NodeVectors<3> ones = NodeVectors<3>::Ones(3, L.slotNodes().size()), g;
    L.gatherSlots(ones, g);
    EXPECT_NEAR(g.row(0).sum(), Real(L.slotNodes().size()), 0);
    for (std::size_t i = 0; i < L.nodeCount(); ++i)
        EXPECT_GE(g(0, i), 1.0);
    // Cell corners are consistent with node coordinates.
    for (std::size_t c = 0; c < L.cellCount(); ++c) {
        const auto& cell = L.cells()[c];
        for (int k = 0; k < 8; ++k) {
            openvdb::Coord ijk = cell.origin;
            for (int a = 0; a < 3; ++a)
                if (k & (1 << a)) ijk[a] += 1;
            EXPECT_EQ(L.nodeCoord(cell.corners[k]), ijk);
            EXPECT_EQ(L.slotNodes()[L.cellSlots()[c * 8 + k]], cell.corners[k]);
        }
    }
}

TEST(SimplexLattice, CoarseCellsAreNested)
{
    // A cell of side 2h and its 8 children of side h: every child simplex lies in one parent
    // simplex (refinement is nested): the centroid of each child simplex satisfies the parent's
    // ordering inequalities with the same permutation class as some parent simplex, and a linear
    // function on the parent is reproduced on the children.
    const auto& axes = KuhnSplit<3>::axis();
    for (int child = 0; child < 8; ++child) {
        for (std::size_t p = 0; p < axes.size(); ++p) {
            // vertices of child simplex in parent units
            std::array<Vec<3>, 4> v;
            Vec<3> o(child & 1, (child >> 1) & 1, (child >> 2) & 1);
            v[0] = 0.5 * o;
            for (int m = 1; m <= 3; ++m) {
                v[m] = v[m - 1];
                v[m][axes[p][m]] += 0.5;
            }
            int parents = 0;
            for (std::size_t q = 0; q < axes.size(); ++q) {
                bool all = true;
                for (int m = 0; m <= 3; ++m)
                    for (int k = 1; k < 3; ++k)
                        all = all && v[m][axes[q][k]] >= v[m][axes[q][k + 1]] - 1e-15;
                parents += all;
            }
            EXPECT_GE(parents, 1) << "child simplex not contained in a parent simplex";
        }
    }
}

TEST(SimplexLattice, GridRoundTrip)
{
    openvdb::initialize();
    const auto L = SimplexLattice<3>::dense(3);
    NodeVectors<3> u = NodeVectors<3>::Random(3, L.nodeCount());
    auto grid = L.toGrid(u);
    EXPECT_EQ(grid->getName(), "displacement");
    EXPECT_EQ(grid->getVectorType(), openvdb::VEC_CONTRAVARIANT_RELATIVE);
    EXPECT_EQ(grid->activeVoxelCount(), openvdb::Index64(L.nodeCount()));
    const NodeVectors<3> back = L.fromGrid(*grid);
    EXPECT_EQ((back - u).norm(), 0.0);
    auto wrong = openvdb::Vec3dGrid::create();
    wrong->setTransform(openvdb::math::Transform::createLinearTransform(0.3));
    EXPECT_THROW(L.fromGrid(*wrong), openvdb::ValueError);
    EXPECT_THROW(SimplexLattice<3>::dense(0), openvdb::ValueError);
}
