/// @file TestAdaptiveLattice.cc
/// @brief Adaptive lattices with hanging nodes: explicit constraints on small examples, 2:1
///        balance (and its violation rejected), continuity of the expanded P1 field across
///        coarse/fine interfaces, reduce = expand^T, unknown counts against the dense lattice,
///        nestedness (prolongation keeps det D phi and the volume energies), and the energy's
///        directional derivative in the constrained space.
#include "energy/EnergyFixture.h"

#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <random>

using namespace vdbmatch;

namespace {

/// Refinement within @a band (Omega units) of the sphere / circle |x - c| = r.
template <int D>
RefinementPredicate<D>
nearSphere(const Vec<D>& center, Real r, Real band)
{
    return [=](const Vec<D>& x, Real radius) {
        return std::abs((x - center).norm() - r) < band + radius;
    };
}

template <int D>
SimplexLattice<D>
sphereLattice(int level, int coarsestLog2Size, Real bandCells = 2,
              const SimplexLattice<D>* coarser = nullptr)
{
    const Real h = 1.0 / Real(1 << level);
    return buildAdaptiveLattice<D>(
        level, coarsestLog2Size, nearSphere<D>(Vec<D>::Constant(0.5), 0.3, bandCells * h), coarser);
}

/// Finds the cell containing a point strictly inside it (index coordinates).
template <int D> class CellFinder
{
public:
    explicit CellFinder(const SimplexLattice<D>& lattice) : mLattice(&lattice)
    {
        for (std::size_t ci = 0; ci < lattice.cellCount(); ++ci) {
            const auto& cell = lattice.cells()[ci];
            const auto s = std::size_t(cell.log2Size);
            if (s >= mIndex.size()) mIndex.resize(s + 1);
            if (!mIndex[s]) mIndex[s] = openvdb::Int32Grid::create(-1);
            mIndex[s]->tree().setValueOn(cell.origin >> s, int32_t(ci));
        }
    }
    /// Index of the cell containing @a p (index coordinates, not on a cell boundary), or -1.
    int32_t find(const Vec<D>& p) const
    {
        for (std::size_t s = 0; s < mIndex.size(); ++s) {
            if (!mIndex[s]) continue;
            openvdb::Coord key(0);
            for (int a = 0; a < D; ++a)
                key[a] = int(std::floor(p[a] / Real(1 << s)));
            const int32_t ci = mIndex[s]->tree().getValue(key);
            if (ci >= 0) return ci;
        }
        return -1;
    }

private:
    const SimplexLattice<D>* mLattice;
    std::vector<openvdb::Int32Grid::Ptr> mIndex;
};

/// Value at the point with index coordinates @a p of the P1 field @a u restricted to cell @a ci
/// (Kuhn barycentric weights; p may lie on the cell's boundary).
template <int D>
Vec<D>
evaluateInCell(const SimplexLattice<D>& lattice, const NodeVectors<D>& u, std::size_t ci,
               const Vec<D>& p)
{
    const auto& cell = lattice.cells()[ci];
    const Real side = Real(1 << cell.log2Size);
    Vec<D> t;
    for (int a = 0; a < D; ++a)
        t[a] = std::clamp((p[a] - Real(cell.origin[a])) / side, Real(0), Real(1));
    std::array<int, D> order;
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int i, int j) { return t[i] > t[j]; });
    Vec<D> value = (1 - t[order[0]]) * u.col(cell.corners[0]);
    int mask = 0;
    for (int m = 1; m <= D; ++m) {
        mask |= 1 << order[m - 1];
        const Real w = m < D ? t[order[m - 1]] - t[order[m]] : t[order[D - 1]];
        value += w * u.col(cell.corners[mask]);
    }
    return value;
}

/// Random values on the free nodes, 0 on the Dirichlet nodes, expanded.
template <int D>
NodeVectors<D>
randomConstrained(const SimplexLattice<D>& lattice, unsigned seed, bool expand = true)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<D> u(D, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        for (int a = 0; a < D; ++a)
            u(a, i) = lattice.isBoundaryNode(i) ? 0 : U(rng);
    if (expand) lattice.expand(u);
    return u;
}

/// The largest jump of @a u across cell faces: for random points on every face of every cell,
/// the value from the cell itself and from the cell on the other side. Also counts the faces
/// between cells of different sizes.
template <int D>
Real
maxJump(const SimplexLattice<D>& lattice, const NodeVectors<D>& u, std::size_t& mixedFaces)
{
    const CellFinder<D> finder(lattice);
    std::mt19937 rng(17);
    std::uniform_real_distribution<Real> U(0.01, 0.99);
    const Real n = Real(lattice.resolution());
    Real jump = 0;
    mixedFaces = 0;
    for (std::size_t ci = 0; ci < lattice.cellCount(); ++ci) {
        const auto& cell = lattice.cells()[ci];
        const Real side = Real(1 << cell.log2Size);
        for (int axis = 0; axis < D; ++axis)
            for (int end = 0; end < 2; ++end) {
                const Real offset = end ? 0.25 : -0.25; // just outside, < half the smallest cell
                for (int k = 0; k < 4; ++k) {
                    Vec<D> p, q;
                    for (int a = 0; a < D; ++a)
                        p[a] = Real(cell.origin[a]) + side * (a == axis ? end : U(rng));
                    q = p;
                    q[axis] += offset;
                    if (q[axis] < 0 || q[axis] > n) continue;
                    const int32_t other = finder.find(q);
                    if (other < 0) continue;
                    if (lattice.cells()[std::size_t(other)].log2Size != cell.log2Size) ++mixedFaces;
                    const Vec<D> a = evaluateInCell(lattice, u, ci, p);
                    const Vec<D> b = evaluateInCell(lattice, u, std::size_t(other), p);
                    jump = std::max(jump, (a - b).cwiseAbs().maxCoeff());
                }
            }
    }
    return jump;
}

template <int D>
void
checkContinuity(int level, int coarsest)
{
    const auto lattice = sphereLattice<D>(level, coarsest);
    ASSERT_GT(lattice.hangingNodeCount(), 0u);
    std::size_t mixed = 0;
    const Real jump = maxJump(lattice, randomConstrained(lattice, 3), mixed);
    EXPECT_GT(mixed, 100u);
    EXPECT_LT(jump, 1e-12);
    // Without the constraints the field jumps: the test sees the interfaces.
    std::size_t mixed2 = 0;
    EXPECT_GT(maxJump(lattice, randomConstrained(lattice, 3, false), mixed2), 1e-2);
}

template <int D>
void
checkConstraintsResolved(const SimplexLattice<D>& lattice)
{
    std::size_t longest = 0;
    for (std::size_t k = 0; k < lattice.hangingNodeCount(); ++k) {
        const std::size_t b = lattice.constraintOffsets()[k],
                          e = lattice.constraintOffsets()[k + 1];
        ASSERT_GE(e - b, 2u);
        longest = std::max(longest, e - b);
        Real sum = 0;
        for (std::size_t j = b; j < e; ++j) {
            const auto m = std::size_t(lattice.constraintMasters()[j]);
            EXPECT_FALSE(lattice.isHangingNode(m));
            EXPECT_GT(lattice.constraintWeights()[j], 0.0);
            if (j > b) {
                EXPECT_LT(lattice.constraintMasters()[j - 1], lattice.constraintMasters()[j]);
            }
            sum += lattice.constraintWeights()[j];
            // A hanging node on the boundary has boundary masters.
            if (lattice.isBoundaryNode(std::size_t(lattice.hangingNodes()[k]))) {
                EXPECT_TRUE(lattice.isBoundaryNode(m));
            }
        }
        EXPECT_NEAR(sum, 1.0, 1e-15);
    }
    std::printf("[ constraints ] %zu hanging nodes, at most %zu masters\n",
                lattice.hangingNodeCount(), longest);
}

/// 2:1 balance: every cell's neighbours across faces, edges and corners (points just outside
/// it) are at most twice as large.
template <int D>
void
checkBalance(const SimplexLattice<D>& lattice)
{
    const CellFinder<D> finder(lattice);
    const Real n = Real(lattice.resolution());
    std::size_t violations = 0;
    for (const auto& cell : lattice.cells()) {
        const Real side = Real(1 << cell.log2Size);
        const int count = D == 3 ? 27 : 9;
        for (int q = 0; q < count; ++q) {
            Vec<D> p;
            int rest = q;
            bool inside = true;
            for (int a = 0; a < D; ++a) {
                const int d = rest % 3 - 1;
                rest /= 3;
                p[a] = Real(cell.origin[a]) + 0.5 * side + d * (0.5 * side + 0.25);
                inside = inside && p[a] > 0 && p[a] < n;
            }
            if (!inside) continue;
            const int32_t other = finder.find(p);
            ASSERT_GE(other, 0);
            violations += lattice.cells()[std::size_t(other)].log2Size > cell.log2Size + 1;
        }
    }
    EXPECT_EQ(violations, 0u);
}

template <int D>
Real
inner(const NodeVectors<D>& a, const NodeVectors<D>& b)
{
    return (a.array() * b.array()).sum();
}

} // namespace

TEST(AdaptiveLattice, ExplicitConstraints2D)
{
    // Level 2 (4 x 4): cells of side 2 at origins (0,0), (0,2), (2,2); cells of side 1 fill
    // [2,4] x [0,2]. Hanging: (2,1) on the edge (2,0)-(2,2) and (3,2) on the edge (2,2)-(4,2).
    auto coarse = openvdb::MaskGrid::create(false);
    auto fine = openvdb::MaskGrid::create(false);
    coarse->tree().setValueOn(openvdb::Coord(0, 0, 0));
    coarse->tree().setValueOn(openvdb::Coord(0, 1, 0));
    coarse->tree().setValueOn(openvdb::Coord(1, 1, 0));
    fine->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(2, 0, 0), openvdb::Coord(3, 1, 0)),
                           true);
    const auto L = SimplexLattice<2>::fromCellMasks(2, {fine, coarse});
    ASSERT_EQ(L.hangingNodeCount(), 2u);
    const int32_t a = L.findNode(openvdb::Coord(2, 1, 0)), b = L.findNode(openvdb::Coord(3, 2, 0));
    EXPECT_TRUE(L.isHangingNode(std::size_t(a)));
    EXPECT_TRUE(L.isHangingNode(std::size_t(b)));
    EXPECT_FALSE(L.isFreeNode(std::size_t(a)));
    EXPECT_TRUE(L.isFreeNode(std::size_t(L.findNode(openvdb::Coord(3, 1, 0)))));
    // Node (3,2): masters (2,2) and (4,2), 1/2 each.
    const auto k = std::size_t(L.hangingIndex(std::size_t(b)));
    ASSERT_EQ(L.constraintOffsets()[k + 1] - L.constraintOffsets()[k], 2u);
    const std::size_t j = L.constraintOffsets()[k];
    EXPECT_EQ(L.nodeCoord(std::size_t(L.constraintMasters()[j])), openvdb::Coord(2, 2, 0));
    EXPECT_EQ(L.nodeCoord(std::size_t(L.constraintMasters()[j + 1])), openvdb::Coord(4, 2, 0));
    EXPECT_EQ(L.constraintWeights()[j], 0.5);
    EXPECT_EQ(L.constraintWeights()[j + 1], 0.5);
    const LatticeStats st = L.stats();
    EXPECT_EQ(st.denseNodes, 25u);
    EXPECT_EQ(st.nodes, 4u + 3u + 4u + 0u + 3u); // rows y = 0..4
    EXPECT_EQ(st.hangingNodes, 2u);
    EXPECT_EQ(st.freeNodes, 2u); // (2,2) and (3,1)
    EXPECT_EQ(st.boundaryNodes, st.nodes - 4u);
    ASSERT_EQ(st.cellsPerLog2Size.size(), 2u);
    EXPECT_EQ(st.cellsPerLog2Size[0], 4u);
    EXPECT_EQ(st.cellsPerLog2Size[1], 3u);
}

TEST(AdaptiveLattice, ExplicitConstraints3D)
{
    // Level 2: every cell of side 2 except the one at origin (2,0,0), which is split into 8.
    // The face centre (2,1,1) of the face x = 2 is constrained to the face's min corner (2,0,0)
    // and max corner (2,2,2); the edge midpoint (2,2,1) to (2,2,0) and (2,2,2).
    auto coarse = openvdb::MaskGrid::create(false);
    coarse->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(1)), true);
    coarse->tree().setValueOff(openvdb::Coord(1, 0, 0));
    auto fine = openvdb::MaskGrid::create(false);
    fine->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(2, 0, 0), openvdb::Coord(3, 1, 1)),
                           true);
    const auto L = SimplexLattice<3>::fromCellMasks(2, {fine, coarse});
    auto masters = [&](const openvdb::Coord& ijk) {
        const int32_t i = L.findNode(ijk);
        EXPECT_GE(i, 0);
        std::vector<std::pair<openvdb::Coord, Real>> out;
        const int32_t k = L.hangingIndex(std::size_t(i));
        if (k < 0) return out;
        for (std::size_t j = L.constraintOffsets()[std::size_t(k)];
             j < L.constraintOffsets()[std::size_t(k) + 1]; ++j)
            out.emplace_back(L.nodeCoord(std::size_t(L.constraintMasters()[j])),
                             L.constraintWeights()[j]);
        return out;
    };
    using P = std::pair<openvdb::Coord, Real>;
    EXPECT_EQ(masters(openvdb::Coord(2, 1, 1)),
              (std::vector<P>{{openvdb::Coord(2, 0, 0), 0.5}, {openvdb::Coord(2, 2, 2), 0.5}}));
    EXPECT_EQ(masters(openvdb::Coord(2, 2, 1)),
              (std::vector<P>{{openvdb::Coord(2, 2, 0), 0.5}, {openvdb::Coord(2, 2, 2), 0.5}}));
    EXPECT_EQ(masters(openvdb::Coord(3, 2, 1)),
              (std::vector<P>{{openvdb::Coord(2, 2, 0), 0.5}, {openvdb::Coord(4, 2, 2), 0.5}}));
    EXPECT_TRUE(masters(openvdb::Coord(3, 1, 1)).empty()); // centre of the split cell: free
    EXPECT_TRUE(L.isFreeNode(std::size_t(L.findNode(openvdb::Coord(3, 1, 1)))));
    EXPECT_EQ(L.freeNodeCount(), 2u); // (2,2,2) and (3,1,1)
    checkConstraintsResolved(L);
    std::size_t mixed = 0;
    EXPECT_LT(maxJump(L, randomConstrained(L, 5), mixed), 1e-12);
    EXPECT_GT(mixed, 0u);
}

TEST(AdaptiveLattice, RejectsUnbalancedAndOverlappingCells)
{
    // 2D level 3: a cell of side 4 next to cells of side 1 (ratio 4).
    auto big = openvdb::MaskGrid::create(false);
    auto small = openvdb::MaskGrid::create(false);
    big->tree().setValueOn(openvdb::Coord(0, 0, 0));
    big->tree().setValueOn(openvdb::Coord(0, 1, 0));
    big->tree().setValueOn(openvdb::Coord(1, 1, 0));
    small->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(4, 0, 0), openvdb::Coord(7, 3, 0)),
                            true);
    EXPECT_THROW(SimplexLattice<2>::fromCellMasks(3, {small, nullptr, big}), openvdb::ValueError);
    // Overlap: a cell of side 2 and one of side 1 at the same origin.
    auto two = openvdb::MaskGrid::create(false);
    auto one = openvdb::MaskGrid::create(false);
    two->tree().setValueOn(openvdb::Coord(0, 0, 0));
    one->tree().setValueOn(openvdb::Coord(0, 0, 0));
    EXPECT_THROW(SimplexLattice<3>::fromCellMasks(3, {one, two}), openvdb::ValueError);
    EXPECT_THROW(buildAdaptiveLattice<2>(3, 4, {}), openvdb::ValueError);
    const auto level2 = SimplexLattice<2>::dense(2);
    EXPECT_THROW(buildAdaptiveLattice<2>(4, 2, {}, &level2), openvdb::ValueError);
}

TEST(AdaptiveLattice, ContinuityAcrossInterfaces2D)
{
    checkContinuity<2>(7, 4);
}
TEST(AdaptiveLattice, ContinuityAcrossInterfaces3D)
{
    checkContinuity<3>(5, 3);
}

TEST(AdaptiveLattice, BalanceAndResolvedConstraints)
{
    const auto L2 = sphereLattice<2>(8, 5);
    checkBalance(L2);
    checkConstraintsResolved(L2);
    const auto L3 = sphereLattice<3>(6, 4);
    checkBalance(L3);
    checkConstraintsResolved(L3);
    // Unrefined: the dense grid of the coarsest cells, no hanging nodes.
    const auto flat = buildAdaptiveLattice<3>(4, 2, {});
    EXPECT_EQ(flat.cellCount(), 64u);
    EXPECT_EQ(flat.hangingNodeCount(), 0u);
    const auto dense = buildAdaptiveLattice<2>(4, 0, {});
    EXPECT_EQ(dense.cellCount(), 256u);
}

TEST(AdaptiveLattice, ReduceIsTransposeOfExpand)
{
    const auto L = sphereLattice<3>(5, 3);
    std::mt19937 rng(2);
    std::uniform_real_distribution<Real> U(-1, 1);
    for (int trial = 0; trial < 3; ++trial) {
        NodeVectors<3> g(3, L.nodeCount()), v(3, L.nodeCount());
        for (Eigen::Index i = 0; i < g.size(); ++i) {
            g.data()[i] = U(rng);
            v.data()[i] = U(rng);
        }
        NodeVectors<3> Pv = v, PTg = g;
        L.expand(Pv);
        L.reduce(PTg);
        EXPECT_NEAR(inner<3>(PTg, v), inner<3>(g, Pv), 1e-12 * std::abs(inner<3>(g, Pv)) + 1e-12);
        for (std::size_t i = 0; i < L.nodeCount(); ++i)
            if (L.isHangingNode(i)) {
                EXPECT_EQ(PTg.col(i).norm(), 0.0);
            } else {
                EXPECT_TRUE(Pv.col(i) == v.col(i));
            }
        // expand is a projection: P P v = P v.
        NodeVectors<3> PPv = Pv;
        L.expand(PPv);
        EXPECT_TRUE(PPv == Pv);
    }
}

TEST(AdaptiveLattice, UnknownsFarBelowDense3D)
{
    // Level 7, refined within 5h of a sphere of radius 0.3, coarsest cells of side 2^-4.
    const auto start = std::chrono::steady_clock::now();
    const auto L =
        buildAdaptiveLattice<3>(7, 3, nearSphere<3>(Vec<3>::Constant(0.5), 0.3, 5.0 / 128));
    const Real seconds =
        std::chrono::duration<Real>(std::chrono::steady_clock::now() - start).count();
    const LatticeStats st = L.stats();
    std::printf("[ level 7 ] cells per size:");
    for (std::size_t s = 0; s < st.cellsPerLog2Size.size(); ++s)
        std::printf(" %zu", st.cellsPerLog2Size[s]);
    std::printf("; nodes %zu, free %zu, hanging %zu, boundary %zu, dense %zu (free/dense %.1f%%), "
                "built in %.2f s\n",
                st.nodes, st.freeNodes, st.hangingNodes, st.boundaryNodes, st.denseNodes,
                100.0 * Real(st.freeNodes) / Real(st.denseNodes), seconds);
    EXPECT_LT(Real(st.freeNodes), 0.25 * Real(st.denseNodes));
    std::size_t hangingOnBoundary = 0;
    for (std::size_t i = 0; i < L.nodeCount(); ++i)
        hangingOnBoundary += L.isHangingNode(i) && L.isBoundaryNode(i);
    EXPECT_EQ(st.freeNodes + st.hangingNodes + st.boundaryNodes, st.nodes + hangingOnBoundary);
    // Points on the sphere lie in cells of side h.
    const multiscale::PiecewiseLinearInterpolator<3> locator(L);
    std::mt19937 rng(1);
    std::normal_distribution<Real> N(0, 1);
    for (int k = 0; k < 200; ++k) {
        Vec<3> d(N(rng), N(rng), N(rng));
        const Vec<3> x = Vec<3>::Constant(0.5) + 0.3 * d.normalized();
        multiscale::PiecewiseLinearInterpolator<3>::Location loc;
        ASSERT_TRUE(locator.locate(x, loc));
        // The simplex's nodes are at most h apart along each axis: a cell of side h.
        for (int m = 1; m <= 3; ++m)
            for (int a = 0; a < 3; ++a)
                EXPECT_LE(std::abs(L.nodeCoord(std::size_t(loc.nodes[m]))[a] -
                                   L.nodeCoord(std::size_t(loc.nodes[0]))[a]),
                          1);
    }
}

TEST(AdaptiveLattice, DeterministicAndThreadIndependent)
{
    const auto pred = nearSphere<3>(Vec<3>::Constant(0.5), 0.3, 2.0 / 32);
    const auto a = buildAdaptiveLattice<3>(5, 3, pred, nullptr, true);
    const auto b = buildAdaptiveLattice<3>(5, 3, pred, nullptr, false);
    ASSERT_EQ(a.nodeCount(), b.nodeCount());
    ASSERT_EQ(a.cellCount(), b.cellCount());
    for (std::size_t i = 0; i < a.nodeCount(); ++i)
        ASSERT_EQ(a.nodeCoord(i), b.nodeCoord(i));
    EXPECT_EQ(a.constraintMasters(), b.constraintMasters());
    EXPECT_EQ(a.constraintWeights(), b.constraintWeights());
}

namespace {

/// Shapes of the energy fixture (circle / ellipse, sphere / ellipsoid) on adaptive lattices
/// refined near the source shape.
template <int D> struct AdaptiveProblem
{
    typename FieldSampler<D>::Ptr shape1, shape2;
    explicit AdaptiveProblem(const EnergyParameters& params, int fieldLevel)
    {
        ShapeFieldOptions opts;
        opts.tau = params.tau;
        shape1 = FieldSampler<D>::build({test::sourceSdf<D>(fieldLevel)}, opts);
        shape2 = FieldSampler<D>::build({test::targetSdf<D>(fieldLevel)}, opts);
    }
    static SimplexLattice<D> lattice(int level, int coarsest,
                                     const SimplexLattice<D>* coarser = nullptr)
    {
        const Real h = 1.0 / Real(1 << level);
        return buildAdaptiveLattice<D>(level, coarsest,
                                       nearSphere<D>(Vec<D>::Constant(0.5), 0.22, 3 * h), coarser);
    }
};

/// A smooth displacement (amplitude @a amplitude, Omega units), 0 on the boundary, projected.
template <int D>
NodeVectors<D>
smoothDisplacement(const SimplexLattice<D>& lattice, Real amplitude, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> U(-1, 1);
    Vec<D> k, phase;
    for (int a = 0; a < D; ++a) {
        k[a] = 2 + std::abs(U(rng));
        phase[a] = 3 * U(rng);
    }
    NodeVectors<D> u(D, lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        const Vec<D> x = lattice.nodePosition(i);
        Real bump = 1;
        for (int a = 0; a < D; ++a)
            bump *= std::sin(M_PI * x[a]);
        for (int a = 0; a < D; ++a)
            u(a, i) = amplitude * bump * std::sin(k[a] * x[(a + 1) % D] * M_PI + phase[a]);
        if (lattice.isBoundaryNode(i)) u.col(i).setZero();
    }
    lattice.expand(u);
    return u;
}

template <int D>
void
checkNestedProlongation(int coarseLevel, int coarsest)
{
    const EnergyParameters params = test::singleTerm(D, 3); // c_vol only
    AdaptiveProblem<D> problem(params, coarseLevel + 2);
    const auto coarse = AdaptiveProblem<D>::lattice(coarseLevel, coarsest);
    const auto fine = AdaptiveProblem<D>::lattice(coarseLevel + 1, coarsest + 1, &coarse);
    ASSERT_GT(coarse.hangingNodeCount(), 0u);
    ASSERT_GT(fine.hangingNodeCount(), 0u);
    // Nested: every fine cell lies in one coarse cell.
    const CellFinder<D> coarseFinder(coarse);
    for (const auto& cell : fine.cells()) {
        Vec<D> centre;
        for (int a = 0; a < D; ++a)
            centre[a] = (Real(cell.origin[a]) + 0.5 * Real(1 << cell.log2Size)) / 2;
        const int32_t ci = coarseFinder.find(centre);
        ASSERT_GE(ci, 0);
        EXPECT_LE(cell.log2Size, coarse.cells()[std::size_t(ci)].log2Size + 1);
    }

    const NodeVectors<D> uc = smoothDisplacement(coarse, 0.03, 11);
    const Energy<D> coarseEnergy(coarse, *problem.shape1, *problem.shape2, params,
                                 EnergyKind::Symmetric);
    const Real sigma = coarseEnergy.sigma();
    const Real detCoarse = coarseEnergy.minJacobianDeterminant(uc);
    ASSERT_GT(detCoarse, 0);
    ASSERT_LT(detCoarse, 0.95);
    EnergyTerms termsCoarse;
    const Real eCoarse = coarseEnergy.value(uc, &termsCoarse);
    ASSERT_TRUE(std::isfinite(eCoarse));

    NodeVectors<D> uf = multiscale::prolongate(coarse, uc, fine);
    const NodeVectors<D> before = uf;
    fine.expand(uf);
    EXPECT_LT((uf - before).cwiseAbs().maxCoeff(), 1e-15); // constraints already satisfied
    const Energy<D> fineEnergy(fine, *problem.shape1, *problem.shape2, params,
                               EnergyKind::Symmetric, sigma);
    EXPECT_NEAR(fineEnergy.minJacobianDeterminant(uf), detCoarse, 1e-12);
    EnergyTerms termsFine;
    const Real eFine = fineEnergy.value(uf, &termsFine);
    EXPECT_NEAR(eFine, eCoarse, 1e-12 * eCoarse);
    EXPECT_NEAR(termsFine.vol[0], termsCoarse.vol[0], 1e-12 * termsCoarse.vol[0]);
    EXPECT_NEAR(termsFine.vol[1], termsCoarse.vol[1], 1e-12 * termsCoarse.vol[1]);
}

/// dE(u + eps w)/deps by central differences equals pairing(g, w) = (P^T g).w for w in the
/// constrained space (random free values, expanded).
template <int D>
void
checkConstrainedGradient(int level, int coarsest)
{
    const EnergyParameters params = EnergyParameters::defaults(D);
    AdaptiveProblem<D> problem(params, level + 2);
    const auto lattice = AdaptiveProblem<D>::lattice(level, coarsest);
    ASSERT_GT(lattice.hangingNodeCount(), 0u);
    const Energy<D> energy(lattice, *problem.shape1, *problem.shape2, params,
                           EnergyKind::Symmetric);
    const NodeVectors<D> u = smoothDisplacement(lattice, 0.5 * lattice.h(), 4);
    NodeVectors<D> g;
    ASSERT_TRUE(std::isfinite(energy.valueAndGradient(u, g)));
    NodeVectors<D> w = randomConstrained(lattice, 9);
    w *= lattice.h();
    // (P^T g).w on the free nodes equals g.(P w) on all non-Dirichlet nodes.
    NodeVectors<D> PTg = g;
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        if (lattice.isBoundaryNode(i)) PTg.col(i).setZero();
    lattice.reduce(PTg);
    Real reduced = 0, full = 0;
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        if (lattice.isFreeNode(i)) reduced += PTg.col(i).dot(w.col(i));
        if (!lattice.isBoundaryNode(i)) full += g.col(i).dot(w.col(i));
    }
    EXPECT_NEAR(reduced, full, 1e-12 * std::abs(full));
    // Fourth-order central difference (as tests/energy/TestEnergyGradient.cc).
    const Real eps = 1e-4;
    auto E = [&](Real t) { return energy.value(u + t * w); };
    const Real fd = (8 * (E(eps) - E(-eps)) - (E(2 * eps) - E(-2 * eps))) / (12 * eps);
    std::printf("[ gradient %dD ] finite difference %.12e, pairing %.12e\n", D, fd, full);
    EXPECT_LE(std::abs(fd - full), 1e-6 * std::abs(full));
}

} // namespace

TEST(AdaptiveLattice, NestedProlongationKeepsDeterminant2D)
{
    checkNestedProlongation<2>(5, 3);
}
TEST(AdaptiveLattice, NestedProlongationKeepsDeterminant3D)
{
    checkNestedProlongation<3>(4, 2);
}

TEST(AdaptiveLattice, ConstrainedGradientMatchesFiniteDifferences2D)
{
    checkConstrainedGradient<2>(6, 3);
}
TEST(AdaptiveLattice, ConstrainedGradientMatchesFiniteDifferences3D)
{
    checkConstrainedGradient<3>(4, 2);
}
