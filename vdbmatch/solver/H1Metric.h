/// @file H1Metric.h
/// @brief The weighted H^1 metric G = M + tau L of the descent (paper sec:numerics) on the P1
///        space of a simplex lattice, and the Riesz map g -> G^{-1} g that turns the L2 gradient
///        of the energy into a descent direction.
///
/// For nodal vector fields v, w (P1 on the Kuhn simplices, one component at a time)
/// @f[ \langle v, w\rangle_G = \int_\Omega v\cdot w + \tau\, Dv : Dw\,dx = v^T (M + \tau L) w, @f]
/// M the P1 mass matrix and L the stiffness matrix, both assembled exactly on the simplices.
/// The Dirichlet nodes (isBoundaryNode, u = 0) are eliminated: the metric acts on the interior
/// nodes only (identity rows and columns), ignores the Dirichlet values of its input and returns
/// 0 there.
///
/// The energy's gradient g_i = dE/du_i is a co-vector (a derivative with respect to nodal
/// values). The H^1 gradient is the vector field r with <r, w>_G = g.w for every w, i.e.
/// r = G^{-1} g; the steepest descent direction in the metric is -r, and
/// ||g||_{G^{-1}} = sqrt(g.r) is the metric norm of the gradient.
///
/// @note The paper says "weighted H^1 metric" and gives no weight. The default is
/// tau = DEFAULT_METRIC_TAU_FACTOR * sigma^2 with sigma = 2h the band half-width of the level
/// (see below): the descent direction is the gradient smoothed over a length sqrt(tau) ~ sigma,
/// the scale of the band terms at that level. Coarser scales are handled by the coarser levels.
///
/// Two solvers for G^{-1}, selected by H1MetricOptions::method:
/// - Direct: Eigen::SimplicialLDLT of G on the interior nodes (AMD ordering), factorised once
///   when the metric is built and reused for every call and every component. Exact.
/// - ConjugateGradient: matrix-free, Jacobi-preconditioned CG on all D components at once,
///   applying G cell by cell in parallel over the lattice blocks (no matrix stored). Because
///   tau = O(h^2), G is spectrally equivalent to the lumped mass matrix and the iteration count
///   is bounded independently of the level (about 10-20 for a relative residual of 1e-8).
/// Auto takes Direct in 2D and in 3D up to DEFAULT_DIRECT_MAX_UNKNOWNS_3D interior nodes, CG
/// beyond (measured: the 3D factorisation at level 6, 250k unknowns, already takes ~?s and ~?MB;
/// at level 7 it would need several GB; see docs/numerics.md).
///
/// Thread-safety: a built metric is immutable; apply() and applyInverse() may be called
/// concurrently. Results do not depend on the number of threads.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <cstddef>
#include <memory>
#include <vector>

namespace vdbmatch {
namespace solver {

using SparseMatrix = Eigen::SparseMatrix<Real>;

/// Default metric weight: tau = DEFAULT_METRIC_TAU_FACTOR * sigma^2 (Omega units squared).
/// Not given by the paper; 1/2 is the "sigma^2/2" filter of heat-kernel smoothing of width
/// sigma, i.e. tau = 2h^2 for sigma = 2h.
constexpr Real DEFAULT_METRIC_TAU_FACTOR = 0.5;
/// Auto method: largest number of interior nodes factorised directly in 3D.
constexpr std::size_t DEFAULT_DIRECT_MAX_UNKNOWNS_3D = 40000;

struct H1MetricOptions
{
    enum class Method { Auto, Direct, ConjugateGradient };
    Method method = Method::Auto;
    /// Auto: 3D lattices with more interior nodes than this use CG.
    std::size_t directMaxUnknowns3D = DEFAULT_DIRECT_MAX_UNKNOWNS_3D;
    /// CG: stop when ||G x - g||_2 <= cgTolerance * ||g||_2, per component.
    Real cgTolerance = 1e-8;
    /// CG: iteration limit (the result is then the last iterate, still a descent direction).
    int cgMaxIterations = 1000;
};

/// Outcome of one applyInverse(): CG iterations (0 for Direct) and the largest relative residual
/// over the components.
struct MetricSolveInfo
{
    int iterations = 0;
    Real relativeResidual = 0;
    bool converged = true;
};

/// Element matrices of a cell of side 1 (the sum over its Kuhn simplices), indexed by corner
/// bitmask as SimplexLattice::Cell::corners: mass M_ref and stiffness L_ref. A cell of side s
/// (Omega units) has s^D M_ref and s^{D-2} L_ref.
template <int D> struct ReferenceCellMatrices
{
    using Matrix = Eigen::Matrix<Real, (1 << D), (1 << D)>;
    Matrix mass, stiffness;
    static const ReferenceCellMatrices& get();
};

/// P1 mass matrix on every node of the lattice (Dirichlet nodes included), exact.
template <int D> SparseMatrix assembleMassMatrix(const SimplexLattice<D>& lattice);
/// P1 stiffness matrix on every node of the lattice (Dirichlet nodes included), exact.
template <int D> SparseMatrix assembleStiffnessMatrix(const SimplexLattice<D>& lattice);

template <int D> class H1Metric
{
public:
    /// @param lattice  must outlive the metric
    /// @param tau      weight of the stiffness, Omega units squared, finite and >= 0
    /// @throw openvdb::ValueError if tau is negative or not finite, or if the direct
    ///        factorisation fails (cannot happen for tau >= 0 and a non-empty interior).
    H1Metric(const SimplexLattice<D>& lattice, Real tau, const H1MetricOptions& opts = {},
             bool threaded = true);
    ~H1Metric();
    H1Metric(const H1Metric&) = delete;
    H1Metric& operator=(const H1Metric&) = delete;

    Real tau() const { return mTau; }
    const SimplexLattice<D>& lattice() const { return *mLattice; }
    /// True if G^{-1} is applied with the sparse factorisation.
    bool isDirect() const { return bool(mFactor); }
    /// Number of interior (non-Dirichlet) nodes.
    std::size_t unknownCount() const { return mInteriorNodes.size(); }
    /// Unknown index of node i, or -1 for a Dirichlet node.
    int32_t unknown(std::size_t node) const { return mUnknown[node]; }

    /// out = G v on the interior nodes, 0 on the Dirichlet nodes (their values in v are
    /// ignored). v and out: D x nodeCount.
    void apply(const NodeVectors<D>& v, NodeVectors<D>& out, bool threaded = true) const;

    /// out = G^{-1} g: the H^1 representative of the co-vector g (D x nodeCount; Dirichlet
    /// entries of g ignored, of out set to 0). @a out may not alias @a g.
    MetricSolveInfo applyInverse(const NodeVectors<D>& g, NodeVectors<D>& out,
                                 bool threaded = true) const;

    /// The pairing g.v summed over the interior nodes (co-vector g, vector v).
    Real pairing(const NodeVectors<D>& g, const NodeVectors<D>& v) const;

    /// Sets the Dirichlet columns of v to 0.
    void zeroDirichlet(NodeVectors<D>& v) const;

    /// G on the interior nodes (unknown numbering), assembled only for the direct method;
    /// assembled on demand otherwise.
    SparseMatrix matrix() const;

private:
    using Factor = Eigen::SimplicialLDLT<SparseMatrix>;

    MetricSolveInfo solveCg(const NodeVectors<D>& g, NodeVectors<D>& x, bool threaded) const;

    const SimplexLattice<D>* mLattice;
    Real mTau;
    H1MetricOptions mOpts;
    std::vector<int32_t> mUnknown;       ///< per node: unknown index or -1
    std::vector<int32_t> mInteriorNodes; ///< per unknown: node index
    Eigen::Matrix<Real, Eigen::Dynamic, 1> mInverseDiagonal; ///< per node, 0 on Dirichlet nodes
    std::unique_ptr<Factor> mFactor;
};

extern template class H1Metric<2>;
extern template class H1Metric<3>;

} // namespace solver
} // namespace vdbmatch
