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
/// Adaptive lattices (hanging nodes, SimplexLattice.h): the unknowns are the free nodes (neither
/// Dirichlet nor hanging); a vector of unknowns x stands for the continuous P1 field P x
/// (SimplexLattice::expand), and the metric on this constrained space is
/// @f[ \langle x, y\rangle = (P x)^T G (P y) = x^T (P^T G P) y. @f]
/// apply() computes P^T G P x (= reduce(G expand(x))) with the assembled matrix below.
/// applyInverse() takes the full co-vector g (every node, as Energy::valueAndGradient returns
/// it), solves (P^T G P) x = P^T g and returns P x (hanging columns interpolated, Dirichlet 0),
/// so that pairing(g, out) = (P^T g).x. On lattices without hanging nodes P is the identity on
/// the interior nodes and every operation is bitwise the same as without the constraints.
///
/// The energy's gradient g_i = dE/du_i is a co-vector (a derivative with respect to nodal
/// values). The H^1 gradient is the vector field r with <r, w>_G = g.w for every w, i.e.
/// r = G^{-1} g; the steepest descent direction in the metric is -r, and
/// ||g||_{G^{-1}} = sqrt(g.r) is the metric norm of the gradient.
///
/// @note The paper says "weighted H^1 metric" and gives no weight. The default is
/// tau = DEFAULT_METRIC_TAU_FACTOR * sigma^2 = sigma^2 / 2 = 2 h^2, with sigma = 2h the band
/// half-width of the level: (1 + tau |k|^2)^{-1}, the symbol of G^{-1} M, agrees to first order
/// in |k|^2 with the Gaussian filter exp(-sigma^2 |k|^2 / 2) of standard deviation sigma, so the
/// descent direction is the L2 gradient smoothed over the scale of the band terms of the level;
/// coarser scales are handled by the coarser levels. Measured (tests/solver/TestDescent.cc
/// problems): factors 0.125 to 8 give final energies within 0.5% of each other; 0.5 gave the
/// lowest, 0.125 the cheapest metric solves (half the CG iterations). match() uses 2 in 2D
/// (Match.h DEFAULT_MATCH_METRIC_TAU_2D: closer to the true map on the correspondence benchmark,
/// docs/numerics.md "Metric weight").
///
/// P^T G P is assembled once, when the metric is built: a compressed-row matrix on the unknowns,
/// one row per free node, built in parallel over the rows from the cells around the node and
/// around the hanging nodes it masters (each row summed in a fixed order, so the matrix does not
/// depend on the thread count). Two solvers for G^{-1}, selected by H1MetricOptions::method:
/// - Direct: Eigen::SimplicialLDLT of that matrix (AMD ordering), factorised once and reused for
///   every call and every component. Exact.
/// - ConjugateGradient: Jacobi-preconditioned CG (the exact diagonal of P^T G P) on all D
///   components at once, one sparse product per iteration in parallel over fixed row chunks.
///   Because tau = O(h^2), G is spectrally equivalent to the mass matrix and the iteration count
///   does not grow with the level.
/// Auto factorises up to DEFAULT_DIRECT_MAX_UNKNOWNS_2D / _3D interior nodes and uses CG beyond.
/// Measured on dense lattices (Release, 2 cores, with the earlier matrix-free CG; factorisation
/// time and peak memory, then time per solve of all D components, CG at 1e-6):
///   2D level 8,   65k unknowns: LDLT 0.35 s,  92 MB, 0.024 s/solve; CG 0.033 s/solve
///   2D level 9,  261k unknowns: LDLT 2.3 s,  273 MB, 0.12 s/solve;  CG 0.16 s/solve
///   2D level 10,  1M unknowns: LDLT 45 s,  1.1 GB, 0.66 s/solve;  CG 0.83 s/solve, 300 MB
///   3D level 4,  3.4k unknowns: LDLT 0.05-0.13 s, 0.003 s/solve;   CG 0.007 s/solve
///   3D level 5,   30k unknowns: LDLT 8.5 s,  194 MB, 0.15 s/solve;  CG 0.06 s/solve
///   3D level 6,  250k unknowns: LDLT > 10 min (stopped);            CG 0.50 s/solve, 123 MB
///   3D level 7,  2.0M unknowns: LDLT not feasible (fill ~ n^{4/3});  CG 4.6 s/solve, 715 MB
/// (the 3D fill of SimplicialLDLT makes it useless beyond level 4). The assembled product is
/// several times cheaper than the matrix-free one it replaced (docs/performance.md).
///
/// Thread-safety: a built metric is immutable; apply() and applyInverse() may be called
/// concurrently. Results do not depend on the number of threads.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/ScratchBuffer.h>
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
/// Auto method: largest number of interior nodes factorised directly, in 2D and in 3D
/// (measured costs in the file comment).
constexpr std::size_t DEFAULT_DIRECT_MAX_UNKNOWNS_2D = 300000;
constexpr std::size_t DEFAULT_DIRECT_MAX_UNKNOWNS_3D = 5000;

struct H1MetricOptions
{
    enum class Method { Auto, Direct, ConjugateGradient };
    Method method = Method::Auto;
    /// Auto: lattices with more interior nodes than this use CG.
    std::size_t directMaxUnknowns2D = DEFAULT_DIRECT_MAX_UNKNOWNS_2D;
    std::size_t directMaxUnknowns3D = DEFAULT_DIRECT_MAX_UNKNOWNS_3D;
    /// CG: stop when ||G x - g||_2 <= cgTolerance * ||g||_2, per component.
    Real cgTolerance = 1e-6;
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
    /// Number of unknowns: free nodes (neither Dirichlet nor hanging; on lattices without
    /// hanging nodes, the interior nodes).
    std::size_t unknownCount() const { return mFreeNodes.size(); }
    /// Unknown index of node i, or -1 for a Dirichlet or hanging node.
    int32_t unknown(std::size_t node) const { return mUnknown[node]; }

    /// out = P^T G P v on the free nodes, 0 on the other nodes: the values of v at the free
    /// nodes are used, its Dirichlet and hanging values are ignored (replaced by 0 and by the
    /// interpolated values). Without hanging nodes: G v on the interior nodes. v and out:
    /// D x nodeCount.
    void apply(const NodeVectors<D>& v, NodeVectors<D>& out, bool threaded = true) const;

    /// out = P (P^T G P)^{-1} P^T g: the H^1 representative of the co-vector g (D x nodeCount,
    /// every node's entry as the energy gradient gives it; Dirichlet entries ignored, hanging
    /// entries moved to their masters), expanded: 0 at the Dirichlet nodes, interpolated at the
    /// hanging nodes. @a out may not alias @a g.
    /// @param initialGuess  optional starting point of the CG iteration (D x nodeCount, e.g. the
    ///                      representative of the previous gradient in a descent; its free-node
    ///                      values are used): fewer iterations when it is close to the solution.
    ///                      Ignored by the direct solver. May alias @a out.
    MetricSolveInfo applyInverse(const NodeVectors<D>& g, NodeVectors<D>& out, bool threaded = true,
                                 const NodeVectors<D>* initialGuess = nullptr) const;

    /// The pairing g.v summed over the non-Dirichlet nodes, hanging ones included (co-vector g,
    /// vector v). For v = P x (e.g. the output of applyInverse) it equals (P^T g).x.
    Real pairing(const NodeVectors<D>& g, const NodeVectors<D>& v) const;

    /// Sets the Dirichlet columns of v to 0 (for co-vectors as well as vectors).
    void zeroDirichlet(NodeVectors<D>& v) const;

    /// Projects a vector onto the constrained space: Dirichlet columns to 0, then hanging
    /// columns interpolated from their masters (SimplexLattice::expand). Use it for initial
    /// guesses; never for co-vectors (gradients).
    void project(NodeVectors<D>& v) const;

    /// P^T G P on the free nodes (unknown numbering), exactly symmetric (a copy of the assembled
    /// matrix, averaged with its transpose).
    SparseMatrix matrix() const;

    /// Stored entries of P^T G P (the compressed-row matrix CG multiplies by).
    std::size_t nonZeroCount() const { return mColumns.size(); }

private:
    using Factor = Eigen::SimplicialLDLT<SparseMatrix>;

    /// Builds mRowBegin, mColumns, mValues: P^T G P in compressed rows over the unknowns.
    void assemble(bool threaded);
    /// y = (P^T G P) x on unknown vectors (D x unknownCount).
    void multiply(const NodeVectors<D>& x, NodeVectors<D>& y, bool threaded) const;
    /// Work arrays of applyInverse (unknown vectors, and the node-sized reduced co-vector).
    struct Workspace
    {
        NodeVectors<D> b, x, r, z, p, q, reduced;
    };
    /// Solves (P^T G P) x = b on unknown vectors; starts from x if @a warm, else from 0.
    MetricSolveInfo solveCg(const NodeVectors<D>& b, NodeVectors<D>& x, Workspace& w, bool threaded,
                            bool warm) const;

    const SimplexLattice<D>* mLattice;
    Real mTau;
    H1MetricOptions mOpts;
    std::vector<int32_t> mUnknown;      ///< per node: unknown index or -1
    std::vector<int32_t> mFreeNodes;    ///< per unknown: node index
    std::vector<int32_t> mSupportNodes; ///< non-Dirichlet nodes (free and hanging), increasing
    std::vector<char> mDirichlet;       ///< per node: 1 on the boundary of Omega
    std::vector<std::size_t> mRowBegin; ///< P^T G P: row i is [mRowBegin[i], mRowBegin[i + 1])
    std::vector<int32_t> mColumns;      ///< ... its columns (unknowns), increasing per row
    std::vector<Real> mValues;          ///< ... and values
    Eigen::Matrix<Real, Eigen::Dynamic, 1> mInverseDiagonal; ///< per unknown: 1 / (P^T G P)_ii
    std::unique_ptr<Factor> mFactor;
    detail::ScratchBuffer<Workspace> mWorkspace; ///< applyInverse's arrays, kept between calls
};

extern template class H1Metric<2>;
extern template class H1Metric<3>;

} // namespace solver
} // namespace vdbmatch
