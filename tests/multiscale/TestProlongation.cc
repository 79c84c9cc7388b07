/// @file TestProlongation.cc
/// @brief Prolongation of piecewise-linear displacements: linear fields and coarse nodal values
///        are reproduced exactly, det D phi and the volume energies are preserved (the Kuhn split
///        is nested), prolongation over two levels equals two single steps, and fine nodes
///        outside the coarse cells get u = 0; a point located in a given cell is where the
///        search puts it.
#include "energy/EnergyFixture.h"

#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <gtest/gtest.h>

#include <random>
#include <set>

using namespace vdbmatch;
using namespace vdbmatch::multiscale;

namespace {

template <int D>
NodeVectors<D>
linearField(const SimplexLattice<D>& lattice, const Mat<D>& A, const Vec<D>& b)
{
    NodeVectors<D> u(D, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        u.col(i) = A * lattice.nodePosition(i) + b;
    return u;
}

template <int D>
void
checkLinearFieldsReproduced()
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<Real> U(-1, 1);
    Mat<D> A;
    Vec<D> b;
    for (int i = 0; i < D; ++i) {
        b[i] = U(rng);
        for (int j = 0; j < D; ++j)
            A(i, j) = U(rng);
    }
    const auto coarse = SimplexLattice<D>::dense(2);
    const auto fine = SimplexLattice<D>::dense(D == 2 ? 5 : 4);
    const NodeVectors<D> uc = linearField(coarse, A, b);
    const NodeVectors<D> uf = prolongate(coarse, uc, fine);
    EXPECT_LT((uf - linearField(fine, A, b)).cwiseAbs().maxCoeff(), 1e-14);

    // Random points (not on nodes): the interpolant of a linear field is the field.
    const PiecewiseLinearInterpolator<D> interpolator(coarse);
    std::uniform_real_distribution<Real> U01(0, 1);
    for (int k = 0; k < 500; ++k) {
        Vec<D> x, value;
        for (int a = 0; a < D; ++a)
            x[a] = U01(rng);
        ASSERT_TRUE(interpolator.evaluate(uc, x, value));
        EXPECT_LT((value - (A * x + b)).cwiseAbs().maxCoeff(), 1e-14);
    }
    Vec<D> outside = Vec<D>::Constant(0.5), value;
    outside[0] = 1.25;
    EXPECT_FALSE(interpolator.evaluate(uc, outside, value));
}

/// Values at the fine nodes that coincide with coarse nodes are copied bit for bit.
template <int D>
void
checkCoarseNodesCopied()
{
    test::MatchingProblem<D> coarseProblem(3, test::sourceSdf<D>(4), test::targetSdf<D>(4),
                                           EnergyParameters::defaults(D), EnergyKind::Symmetric);
    const auto& coarse = *coarseProblem.lattice;
    const NodeVectors<D> uc = coarseProblem.randomDisplacement(3, 0.2 * coarse.h());
    const auto fine = SimplexLattice<D>::dense(4);
    const NodeVectors<D> uf = prolongate(coarse, uc, fine);
    for (std::size_t i = 0; i < coarse.nodeCount(); ++i) {
        const int32_t j = fine.findNode(coarse.nodeCoord(i) << 1);
        ASSERT_GE(j, 0);
        for (int a = 0; a < D; ++a)
            EXPECT_EQ(uf(a, j), uc(a, i));
    }
    // Dirichlet nodes of the fine lattice stay at 0.
    for (std::size_t j = 0; j < fine.nodeCount(); ++j)
        if (fine.isBoundaryNode(j)) {
            EXPECT_EQ(uf.col(j).cwiseAbs().maxCoeff(), 0.0);
        }
}

/// det D phi and the volume energies survive prolongation, over one and over two levels.
template <int D>
void
checkDeterminantAndVolumeEnergyPreserved(int coarseLevel)
{
    const int fieldLevel = coarseLevel + 2;
    const EnergyParameters params = test::singleTerm(D, 3); // c_vol only
    test::MatchingProblem<D> coarseProblem(coarseLevel, test::sourceSdf<D>(fieldLevel),
                                           test::targetSdf<D>(fieldLevel), params,
                                           EnergyKind::Symmetric);
    const auto& coarse = *coarseProblem.lattice;
    // Amplitude 0.6 h with noise: strongly distorted but not inverted simplices.
    const NodeVectors<D> uc = coarseProblem.randomDisplacement(11, 0.6 * coarse.h());
    const Real sigma = coarseProblem.energy->sigma();
    const Real detCoarse = coarseProblem.energy->minJacobianDeterminant(uc);
    ASSERT_GT(detCoarse, 0);
    ASSERT_LT(detCoarse, 0.9);
    EnergyTerms termsCoarse;
    const Real eCoarse = coarseProblem.energy->value(uc, &termsCoarse);
    ASSERT_TRUE(std::isfinite(eCoarse));

    for (int step = 1; step <= 2; ++step) {
        const auto fine = SimplexLattice<D>::dense(coarseLevel + step);
        const NodeVectors<D> uf = prolongate(coarse, uc, fine);
        // The same sigma on both lattices: the volume weight c_vol sigma^theta is equal.
        const Energy<D> fineEnergy(fine, *coarseProblem.shape1, *coarseProblem.shape2, params,
                                   EnergyKind::Symmetric, sigma);
        EXPECT_NEAR(fineEnergy.minJacobianDeterminant(uf), detCoarse, 1e-13)
            << "levels " << coarseLevel << " -> " << coarseLevel + step;
        EnergyTerms termsFine;
        const Real eFine = fineEnergy.value(uf, &termsFine);
        EXPECT_NEAR(eFine, eCoarse, 1e-12 * eCoarse);
        EXPECT_NEAR(termsFine.vol[0], termsCoarse.vol[0], 1e-12 * termsCoarse.vol[0]);
        EXPECT_NEAR(termsFine.vol[1], termsCoarse.vol[1], 1e-12 * termsCoarse.vol[1]);

        if (step == 2) {
            // Two single steps give the same values as one double step.
            const auto middle = SimplexLattice<D>::dense(coarseLevel + 1);
            const NodeVectors<D> twice = prolongate(middle, prolongate(coarse, uc, middle), fine);
            EXPECT_LT((twice - uf).cwiseAbs().maxCoeff(), 1e-15);
        }
    }
}

/// A coarse lattice covering only part of Omega: fine nodes outside its cells get u = 0, nodes
/// inside (closed cells) get the interpolant.
template <int D>
void
checkOutsideNodesGetZero()
{
    const openvdb::CoordBBox cellBox(openvdb::Coord(1), openvdb::Coord(2));
    const auto coarse = SimplexLattice<D>::box(2, cellBox);
    const Mat<D> A = Mat<D>::Identity();
    const Vec<D> b = Vec<D>::Constant(0.25);
    const NodeVectors<D> uc = linearField(coarse, A, b);
    const auto fine = SimplexLattice<D>::dense(4);
    const NodeVectors<D> uf = prolongate(coarse, uc, fine);
    std::size_t inside = 0;
    for (std::size_t i = 0; i < fine.nodeCount(); ++i) {
        const Vec<D> x = fine.nodePosition(i);
        // Cells 1..2 of level 2 cover [0.25, 0.75]^D.
        const bool in = (x.array() >= 0.25).all() && (x.array() <= 0.75).all();
        if (in) {
            ++inside;
            EXPECT_LT((uf.col(i) - (A * x + b)).cwiseAbs().maxCoeff(), 1e-15);
        } else {
            EXPECT_EQ(uf.col(i).cwiseAbs().maxCoeff(), 0.0);
        }
    }
    EXPECT_EQ(inside, std::size_t(std::pow(9, D)));
}

} // namespace

TEST(Prolongation, LinearFieldsReproduced2D)
{
    checkLinearFieldsReproduced<2>();
}
TEST(Prolongation, LinearFieldsReproduced3D)
{
    checkLinearFieldsReproduced<3>();
}

TEST(Prolongation, CoarseNodesCopied2D)
{
    checkCoarseNodesCopied<2>();
}
TEST(Prolongation, CoarseNodesCopied3D)
{
    checkCoarseNodesCopied<3>();
}

TEST(Prolongation, DeterminantAndVolumeEnergyPreserved2D)
{
    checkDeterminantAndVolumeEnergyPreserved<2>(4);
}
TEST(Prolongation, DeterminantAndVolumeEnergyPreserved3D)
{
    checkDeterminantAndVolumeEnergyPreserved<3>(3);
}

TEST(Prolongation, OutsideNodesGetZero2D)
{
    checkOutsideNodesGetZero<2>();
}
TEST(Prolongation, OutsideNodesGetZero3D)
{
    checkOutsideNodesGetZero<3>();
}

TEST(Prolongation, RejectsCoarserTarget)
{
    const auto coarse = SimplexLattice<2>::dense(3);
    const auto finer = SimplexLattice<2>::dense(4);
    const NodeVectors<2> onFiner = NodeVectors<2>::Zero(2, finer.nodeCount());
    const NodeVectors<2> wrongSize = NodeVectors<2>::Zero(2, 3);
    EXPECT_THROW(prolongate(finer, onFiner, coarse), openvdb::ValueError);
    EXPECT_THROW(prolongate(coarse, wrongSize, finer), openvdb::ValueError);
}

namespace {

/// On an adaptive lattice (cells of four sizes), every point of the open interior of a cell is
/// located by locateInCell() exactly as by the search (nodes and weights to the last bit), and
/// Cursor::cell() names the cell the search uses, also for points on faces.
template <int D>
void
checkLocateInCellIsTheSearch()
{
    const Vec<D> centre = Vec<D>::Constant(0.41);
    const auto lattice = buildAdaptiveLattice<D>(
        6, 3, [&](const Vec<D>& c, Real radius) { return (c - centre).norm() < 0.2 + radius; });
    std::set<int> sizes;
    for (const auto& cell : lattice.cells())
        sizes.insert(cell.log2Size);
    ASSERT_GE(sizes.size(), 3u);
    const PiecewiseLinearInterpolator<D> phi(lattice);
    typename PiecewiseLinearInterpolator<D>::Cursor cursor(phi);
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> U(0, 1);
    const Real h = lattice.h();
    std::size_t interior = 0, onFaces = 0;
    for (std::size_t ci = 0; ci < lattice.cells().size(); ci += 7) {
        const auto& cell = lattice.cells()[ci];
        const Real side = h * Real(1 << cell.log2Size);
        for (int k = 0; k < 4; ++k) {
            // Dyadic points of the cell (as the output grid's nodes are), some on its faces.
            Vec<D> x;
            bool inside = true;
            for (int a = 0; a < D; ++a) {
                const int steps = int(U(rng) * 16); // 0..15 sixteenths of the side
                x[a] = cell.origin[a] * h + side * steps / 16.0;
                inside = inside && steps > 0;
            }
            typename PiecewiseLinearInterpolator<D>::Location searched, direct;
            ASSERT_TRUE(phi.locate(x, searched));
            const int32_t found = cursor.cell(x);
            ASSERT_GE(found, 0);
            phi.locateInCell(std::size_t(found), x, direct);
            EXPECT_EQ(direct.nodes, searched.nodes);
            EXPECT_EQ(direct.weights, searched.weights);
            if (inside) {
                EXPECT_EQ(found, int32_t(ci));
                phi.locateInCell(ci, x, direct);
                EXPECT_EQ(direct.nodes, searched.nodes);
                EXPECT_EQ(direct.weights, searched.weights);
                ++interior;
            } else {
                ++onFaces;
            }
        }
    }
    EXPECT_GT(interior, 100u);
    EXPECT_GT(onFaces, 10u);
    Vec<D> outside = Vec<D>::Constant(0.5);
    outside[0] = 1.5;
    EXPECT_EQ(cursor.cell(outside), -1);
}

} // namespace

TEST(Prolongation, LocateInCellIsTheSearch2D)
{
    checkLocateInCellIsTheSearch<2>();
}
TEST(Prolongation, LocateInCellIsTheSearch3D)
{
    checkLocateInCellIsTheSearch<3>();
}
