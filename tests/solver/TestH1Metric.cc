/// @file TestH1Metric.cc
/// @brief The weighted H^1 metric G = M + tau L: exact P1 mass and stiffness on the Kuhn
///        simplices, G symmetric positive definite, G^{-1} M u = u for tau = 0, G^{-1} of a
///        constant field smooth and equal to it away from the boundary, direct and CG solvers
///        agreeing, thread-count independence; on adaptive lattices (hanging nodes) the
///        constrained metric P^T G P: SPD, matrix-free = assembled, direct = CG, the pairing
///        identity, CG iteration counts against the dense lattice.
#include <vdbmatch/lattice/AdaptiveLattice.h>
#include <vdbmatch/solver/H1Metric.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

using namespace vdbmatch;
using namespace vdbmatch::solver;

namespace {

using Method = H1MetricOptions::Method;

H1MetricOptions
withMethod(Method method, Real cgTolerance = 1e-12)
{
    H1MetricOptions o;
    o.method = method;
    o.cgTolerance = cgTolerance;
    return o;
}

/// Default weight of a level: tau = DEFAULT_METRIC_TAU_FACTOR sigma^2, sigma = 2h.
Real
defaultTau(Real h)
{
    return DEFAULT_METRIC_TAU_FACTOR * 4 * h * h;
}

template <int D>
Eigen::VectorXd
nodalValues(const SimplexLattice<D>& lattice, const Vec<D>& a, Real b)
{
    Eigen::VectorXd f(lattice.nodeCount());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        f[Eigen::Index(i)] = a.dot(lattice.nodePosition(i)) + b;
    return f;
}

/// int_{(0,1)^D} (a.x + b)(c.x + d) dx
template <int D>
Real
integralOfProduct(const Vec<D>& a, Real b, const Vec<D>& c, Real d)
{
    Real s = b * d + 0.5 * (b * c.sum() + d * a.sum());
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            s += a[i] * c[j] * (i == j ? 1.0 / 3.0 : 0.25);
    return s;
}

/// P1 mass and stiffness are exact on linear fields; also on a lattice of cells of side 2h,
/// which checks the scaling with the cell size.
template <int D>
void
checkExactMatrices(const SimplexLattice<D>& lattice)
{
    const SparseMatrix M = assembleMassMatrix(lattice);
    const SparseMatrix L = assembleStiffnessMatrix(lattice);
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> U(-1, 1);
    for (int trial = 0; trial < 5; ++trial) {
        Vec<D> a, c;
        for (int i = 0; i < D; ++i) {
            a[i] = U(rng);
            c[i] = U(rng);
        }
        const Real b = U(rng), d = U(rng);
        const Eigen::VectorXd f = nodalValues(lattice, a, b), g = nodalValues(lattice, c, d);
        EXPECT_NEAR(f.dot(M * g), integralOfProduct<D>(a, b, c, d), 1e-13);
        EXPECT_NEAR(f.dot(L * g), a.dot(c), 1e-12);
    }
    // Constants are in the kernel of L.
    const Eigen::VectorXd one = Eigen::VectorXd::Ones(Eigen::Index(lattice.nodeCount()));
    EXPECT_LT((L * one).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_NEAR(one.dot(M * one), 1.0, 1e-14);
}

template <int D>
void
checkSymmetricPositiveDefinite(Method method)
{
    const auto lattice = SimplexLattice<D>::dense(D == 2 ? 5 : 3);
    const H1Metric<D> metric(lattice, defaultTau(lattice.h()), withMethod(method));
    const SparseMatrix G = metric.matrix();
    EXPECT_EQ(std::size_t(G.rows()), metric.unknownCount());
    EXPECT_EQ(SparseMatrix(G - SparseMatrix(G.transpose())).norm(), 0.0);
    Eigen::SimplicialLDLT<SparseMatrix> ldlt(G);
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    EXPECT_GT(ldlt.vectorD().minCoeff(), 0.0);

    // The matrix-free apply() agrees with the assembled matrix; v^T G v > 0; Dirichlet rows 0.
    std::mt19937 rng(3);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<D> v(D, lattice.nodeCount()), Gv;
    for (Eigen::Index i = 0; i < v.size(); ++i)
        v.data()[i] = U(rng);
    metric.apply(v, Gv);
    for (int c = 0; c < D; ++c) {
        Eigen::VectorXd vc(G.rows()), Gvc(G.rows());
        for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
            const int32_t k = metric.unknown(i);
            if (k < 0) {
                EXPECT_EQ(Gv(c, i), 0.0);
                continue;
            }
            vc[k] = v(c, i);
            Gvc[k] = Gv(c, i);
        }
        EXPECT_LT((G * vc - Gvc).cwiseAbs().maxCoeff(), 1e-15);
        EXPECT_GT(vc.dot(G * vc), 0.0);
    }
}

/// tau = 0: G = M on the interior nodes, so G^{-1} (M u) = u for u = 0 on the boundary.
template <int D>
void
checkMassInverse(Method method)
{
    const auto lattice = SimplexLattice<D>::dense(D == 2 ? 5 : 3);
    const H1Metric<D> metric(lattice, 0.0, withMethod(method));
    const SparseMatrix M = assembleMassMatrix(lattice);
    std::mt19937 rng(9);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<D> u(D, lattice.nodeCount());
    for (Eigen::Index i = 0; i < u.size(); ++i)
        u.data()[i] = U(rng);
    metric.zeroDirichlet(u);
    const NodeVectors<D> Mu = (M * u.transpose()).transpose();
    NodeVectors<D> r;
    const MetricSolveInfo info = metric.applyInverse(Mu, r);
    EXPECT_TRUE(info.converged);
    EXPECT_LT((r - u).cwiseAbs().maxCoeff(), 1e-10);
}

/// g = M c (the co-vector of a constant field c): G^{-1} g equals c away from the boundary
/// layer of width ~ sqrt(tau), rises monotonically from 0 at the boundary, and never overshoots.
template <int D>
void
checkConstantFieldSmooth(Method method)
{
    const int level = D == 2 ? 6 : 4;
    const auto lattice = SimplexLattice<D>::dense(level);
    const Real h = lattice.h(), tau = defaultTau(h);
    const H1Metric<D> metric(lattice, tau, withMethod(method));
    const SparseMatrix M = assembleMassMatrix(lattice);
    Vec<D> c;
    for (int a = 0; a < D; ++a)
        c[a] = 1.0 + a;
    const NodeVectors<D> constant = c.replicate(1, Eigen::Index(lattice.nodeCount()));
    const NodeVectors<D> g = (M * constant.transpose()).transpose();
    NodeVectors<D> r;
    metric.applyInverse(g, r);

    const Real layer = 10 * std::sqrt(tau); // e^{-10} ~ 5e-5
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        const Vec<D> x = lattice.nodePosition(i);
        const Real dist = std::min(x.minCoeff(), 1 - x.maxCoeff());
        for (int a = 0; a < D; ++a) {
            EXPECT_GE(r(a, i), -1e-12 * c[a]);
            EXPECT_LE(r(a, i), c[a] * (1 + 1e-9));
            if (dist > layer) {
                EXPECT_NEAR(r(a, i), c[a], 1e-3 * c[a]);
            }
        }
    }
    // Along the line through the centre parallel to axis 0: monotone up to the middle.
    const int n = lattice.resolution();
    openvdb::Coord ijk(0);
    for (int a = 1; a < D; ++a)
        ijk[a] = n / 2;
    Real previous = -1;
    for (int k = 0; k <= n / 2; ++k) {
        ijk[0] = k;
        const int32_t i = lattice.findNode(ijk);
        ASSERT_GE(i, 0);
        EXPECT_GE(r(0, i), previous - 1e-12);
        previous = r(0, i);
    }
}

} // namespace

TEST(H1Metric, ExactMassAndStiffness2D)
{
    checkExactMatrices<2>(SimplexLattice<2>::dense(3));
    auto coarseCells = openvdb::MaskGrid::create(false);
    coarseCells->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(3, 3, 0)),
                                  true, true);
    checkExactMatrices<2>(SimplexLattice<2>::fromCellMasks(3, {nullptr, coarseCells}));
}
TEST(H1Metric, ExactMassAndStiffness3D)
{
    checkExactMatrices<3>(SimplexLattice<3>::dense(3));
    auto coarseCells = openvdb::MaskGrid::create(false);
    coarseCells->tree().denseFill(openvdb::CoordBBox(openvdb::Coord(0), openvdb::Coord(3)), true,
                                  true);
    checkExactMatrices<3>(SimplexLattice<3>::fromCellMasks(3, {nullptr, coarseCells}));
}

TEST(H1Metric, SymmetricPositiveDefinite2D)
{
    checkSymmetricPositiveDefinite<2>(Method::Direct);
    checkSymmetricPositiveDefinite<2>(Method::ConjugateGradient);
}
TEST(H1Metric, SymmetricPositiveDefinite3D)
{
    checkSymmetricPositiveDefinite<3>(Method::Direct);
    checkSymmetricPositiveDefinite<3>(Method::ConjugateGradient);
}

TEST(H1Metric, MassInverseForTauZero2D)
{
    checkMassInverse<2>(Method::Direct);
    checkMassInverse<2>(Method::ConjugateGradient);
}
TEST(H1Metric, MassInverseForTauZero3D)
{
    checkMassInverse<3>(Method::Direct);
    checkMassInverse<3>(Method::ConjugateGradient);
}

TEST(H1Metric, ConstantFieldIsSmooth2D)
{
    checkConstantFieldSmooth<2>(Method::Direct);
    checkConstantFieldSmooth<2>(Method::ConjugateGradient);
}
TEST(H1Metric, ConstantFieldIsSmooth3D)
{
    checkConstantFieldSmooth<3>(Method::Direct);
    checkConstantFieldSmooth<3>(Method::ConjugateGradient);
}

TEST(H1Metric, DirectAndConjugateGradientAgree)
{
    const auto lattice = SimplexLattice<3>::dense(4);
    const Real tau = defaultTau(lattice.h());
    const H1Metric<3> direct(lattice, tau, withMethod(Method::Direct));
    const H1Metric<3> cg(lattice, tau, withMethod(Method::ConjugateGradient, 1e-10));
    const H1Metric<3> automatic(lattice, tau);
    const auto level5 = SimplexLattice<3>::dense(5);
    EXPECT_TRUE(direct.isDirect());
    EXPECT_FALSE(cg.isDirect());
    EXPECT_TRUE(automatic.isDirect()); // 15^3 = 3375 unknowns <= DEFAULT_DIRECT_MAX_UNKNOWNS_3D
    EXPECT_FALSE(H1Metric<3>(level5, tau).isDirect()); // 29791 unknowns

    std::mt19937 rng(4);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<3> g(3, lattice.nodeCount()), rd, rc;
    for (Eigen::Index i = 0; i < g.size(); ++i)
        g.data()[i] = U(rng);
    direct.applyInverse(g, rd);
    const MetricSolveInfo info = cg.applyInverse(g, rc);
    EXPECT_TRUE(info.converged);
    EXPECT_GT(info.iterations, 0);
    EXPECT_LT((rd - rc).norm(), 1e-8 * rd.norm());
    // <g, G^{-1} g> > 0: the direction -G^{-1} g descends.
    EXPECT_GT(direct.pairing(g, rd), 0.0);
}

TEST(H1Metric, ThreadCountIndependent)
{
    const auto lattice = SimplexLattice<3>::dense(5);
    const H1Metric<3> metric(lattice, defaultTau(lattice.h()),
                             withMethod(Method::ConjugateGradient, 1e-6));
    std::mt19937 rng(8);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<3> g(3, lattice.nodeCount()), serial, threaded;
    for (Eigen::Index i = 0; i < g.size(); ++i)
        g.data()[i] = U(rng);
    metric.applyInverse(g, serial, false);
    metric.applyInverse(g, threaded, true);
    EXPECT_TRUE(serial == threaded);
}

TEST(H1Metric, RejectsNegativeTau)
{
    const auto lattice = SimplexLattice<2>::dense(3);
    EXPECT_THROW(H1Metric<2>(lattice, -1.0), openvdb::ValueError);
}

namespace {

/// Adaptive lattice refined within 2h of the sphere / circle of radius 0.3 at the centre.
template <int D>
SimplexLattice<D>
adaptiveLattice(int level, int coarsest)
{
    const Real h = 1.0 / Real(1 << level);
    return buildAdaptiveLattice<D>(level, coarsest, [h](const Vec<D>& x, Real radius) {
        return std::abs((x - Vec<D>::Constant(0.5)).norm() - 0.3) < 2 * h + radius;
    });
}

template <int D>
NodeVectors<D>
randomNodeVectors(std::size_t n, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<D> v(D, Eigen::Index(n));
    for (Eigen::Index i = 0; i < v.size(); ++i)
        v.data()[i] = U(rng);
    return v;
}

template <int D>
void
checkConstrainedMetric(int level, int coarsest)
{
    const auto lattice = adaptiveLattice<D>(level, coarsest);
    ASSERT_GT(lattice.hangingNodeCount(), 0u);
    const Real tau = defaultTau(lattice.h());
    const H1Metric<D> direct(lattice, tau, withMethod(Method::Direct));
    const H1Metric<D> cg(lattice, tau, withMethod(Method::ConjugateGradient, 1e-10));
    EXPECT_EQ(direct.unknownCount(), lattice.freeNodeCount());

    // P^T G P: symmetric positive definite.
    const SparseMatrix A = direct.matrix();
    ASSERT_EQ(std::size_t(A.rows()), lattice.freeNodeCount());
    EXPECT_EQ(SparseMatrix(A - SparseMatrix(A.transpose())).norm(), 0.0);
    Eigen::SimplicialLDLT<SparseMatrix> ldlt(A);
    ASSERT_EQ(ldlt.info(), Eigen::Success);
    EXPECT_GT(ldlt.vectorD().minCoeff(), 0.0);

    // apply() = reduce(G expand(v)) on the free nodes, 0 elsewhere, with G = M + tau L
    // assembled on every node independently of the metric's own row-by-row assembly.
    const NodeVectors<D> v = randomNodeVectors<D>(lattice.nodeCount(), 3);
    NodeVectors<D> Av;
    cg.apply(v, Av);
    const SparseMatrix G =
        assembleMassMatrix<D>(lattice) + tau * assembleStiffnessMatrix<D>(lattice);
    NodeVectors<D> expanded = v;
    direct.project(expanded);
    NodeVectors<D> reference = (G * expanded.transpose()).transpose();
    direct.zeroDirichlet(reference);
    lattice.reduce(reference);
    const Real refScale = reference.cwiseAbs().maxCoeff();
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        if (!lattice.isFreeNode(i)) {
            EXPECT_EQ(Av.col(i).cwiseAbs().maxCoeff(), 0.0);
            continue;
        }
        EXPECT_LT((Av.col(i) - reference.col(i)).cwiseAbs().maxCoeff(), 1e-13 * refScale);
    }
    // And matrix() is the same operator.
    for (int c = 0; c < D; ++c) {
        Eigen::VectorXd vc(A.rows()), Avc(A.rows());
        for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
            const int32_t k = cg.unknown(i);
            if (k < 0) continue;
            vc[k] = v(c, i);
            Avc[k] = Av(c, i);
        }
        EXPECT_LT((A * vc - Avc).cwiseAbs().maxCoeff(), 1e-14 * (A * vc).cwiseAbs().maxCoeff());
    }

    // Direct and CG agree; the result is expanded; pairing(g, r) = (P^T g).x.
    const NodeVectors<D> g = randomNodeVectors<D>(lattice.nodeCount(), 4);
    NodeVectors<D> rd, rc;
    direct.applyInverse(g, rd);
    const MetricSolveInfo info = cg.applyInverse(g, rc);
    EXPECT_TRUE(info.converged);
    EXPECT_LT((rd - rc).norm(), 1e-6 * rd.norm());
    NodeVectors<D> projected = rd;
    direct.project(projected);
    EXPECT_LT((projected - rd).cwiseAbs().maxCoeff(), 1e-15 * rd.cwiseAbs().maxCoeff());
    NodeVectors<D> PTg = g;
    direct.zeroDirichlet(PTg);
    lattice.reduce(PTg);
    Real reduced = 0;
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        if (lattice.isFreeNode(i)) reduced += PTg.col(i).dot(rd.col(i));
    EXPECT_NEAR(direct.pairing(g, rd), reduced, 1e-12 * std::abs(reduced));
    EXPECT_GT(reduced, 0.0);
    // (P^T G P) x = P^T g: apply() to the result gives back P^T g on the free nodes.
    NodeVectors<D> back;
    direct.apply(rd, back);
    Real err = 0, scale = 0;
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i)
        if (lattice.isFreeNode(i)) {
            err = std::max(err, (back.col(i) - PTg.col(i)).cwiseAbs().maxCoeff());
            scale = std::max(scale, PTg.col(i).cwiseAbs().maxCoeff());
        }
    EXPECT_LT(err, 1e-9 * scale);
}

} // namespace

TEST(H1Metric, ConstrainedMetricOnAdaptiveLattice2D)
{
    checkConstrainedMetric<2>(6, 3);
}
TEST(H1Metric, ConstrainedMetricOnAdaptiveLattice3D)
{
    checkConstrainedMetric<3>(4, 2);
}

TEST(H1Metric, ConjugateGradientIterationsAdaptiveVsDense)
{
    // Default tolerance 1e-6 and tau; a smooth right-hand side (the mass of a constant field).
    for (int level : {5, 6}) {
        const auto adaptive = adaptiveLattice<3>(level, level - 3);
        const auto dense = SimplexLattice<3>::dense(level);
        int iterations[2] = {0, 0};
        Real seconds[2] = {0, 0};
        const SimplexLattice<3>* lattices[2] = {&adaptive, &dense};
        for (int k = 0; k < 2; ++k) {
            const auto& L = *lattices[k];
            const H1Metric<3> metric(L, defaultTau(L.h()),
                                     withMethod(Method::ConjugateGradient, 1e-6));
            const NodeVectors<3> g = randomNodeVectors<3>(L.nodeCount(), 6);
            NodeVectors<3> r;
            const auto start = std::chrono::steady_clock::now();
            const MetricSolveInfo info = metric.applyInverse(g, r);
            seconds[k] =
                std::chrono::duration<Real>(std::chrono::steady_clock::now() - start).count();
            EXPECT_TRUE(info.converged);
            iterations[k] = info.iterations;
        }
        std::printf("[ CG 3D level %d ] adaptive: %zu unknowns, %d iterations, %.3f s; dense: "
                    "%zu unknowns, %d iterations, %.3f s\n",
                    level, adaptive.freeNodeCount(), iterations[0], seconds[0],
                    dense.freeNodeCount(), iterations[1], seconds[1]);
        // The constrained metric stays well conditioned (Jacobi approximation included).
        EXPECT_LT(iterations[0], 3 * iterations[1] + 20);
    }
}

TEST(H1Metric, WarmStartedConjugateGradient)
{
    // applyInverse with an initial guess: the same solution to the tolerance, no iteration from
    // the solution itself, fewer from a nearby guess; the guess may alias the output.
    const auto lattice = SimplexLattice<3>::dense(4);
    const Real tau = defaultTau(lattice.h());
    const H1Metric<3> direct(lattice, tau, withMethod(Method::Direct));
    const H1Metric<3> cg(lattice, tau, withMethod(Method::ConjugateGradient, 1e-8));
    std::mt19937 rng(5);
    std::uniform_real_distribution<Real> U(-1, 1);
    NodeVectors<3> g(3, lattice.nodeCount()), exact, cold, warm;
    for (Eigen::Index i = 0; i < g.size(); ++i)
        g.data()[i] = U(rng);
    direct.applyInverse(g, exact);
    const MetricSolveInfo coldInfo = cg.applyInverse(g, cold);
    EXPECT_LT((cold - exact).norm(), 1e-6 * exact.norm());

    NodeVectors<3> guess = exact;
    const MetricSolveInfo fromSolution = cg.applyInverse(g, warm, true, &guess);
    EXPECT_EQ(fromSolution.iterations, 0);
    EXPECT_LT((warm - exact).norm(), 1e-6 * exact.norm());

    // A nearby guess (5% perturbation, Dirichlet values garbage: they are ignored).
    guess = exact;
    for (Eigen::Index i = 0; i < guess.size(); ++i)
        guess.data()[i] += 0.05 * exact.cwiseAbs().maxCoeff() * U(rng);
    warm = guess; // aliasing: the guess is the output buffer
    const MetricSolveInfo near = cg.applyInverse(g, warm, true, &warm);
    EXPECT_TRUE(near.converged);
    EXPECT_LT(near.iterations, coldInfo.iterations);
    EXPECT_LT((warm - exact).norm(), 1e-6 * exact.norm());
    for (std::size_t i = 0; i < lattice.nodeCount(); ++i) {
        if (lattice.isBoundaryNode(i)) {
            EXPECT_EQ(warm.col(i).norm(), 0.0);
        }
    }
    // The direct solver ignores the guess.
    NodeVectors<3> viaDirect;
    direct.applyInverse(g, viaDirect, true, &guess);
    EXPECT_TRUE(viaDirect == exact);
}
