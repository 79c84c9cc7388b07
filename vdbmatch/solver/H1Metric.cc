/// @file H1Metric.cc
#include "H1Metric.h"

#include <openvdb/Exceptions.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdbmatch {
namespace solver {

namespace {

template <int D>
constexpr Real
factorial()
{
    return D == 2 ? 2.0 : 6.0;
}

/// Nodes per chunk of the CG vector passes (fixed, so that sums do not depend on threads).
constexpr Eigen::Index CG_CHUNK = 4096;

/// True if corner bitmasks a and b lie in a common Kuhn simplex (one is a subset of the other):
/// exactly the nonzero entries of the element matrices.
constexpr bool
comparable(int a, int b)
{
    return (a & b) == a || (a & b) == b;
}

/// Side of a cell in Omega units.
template <int D>
Real
cellSide(const SimplexLattice<D>& lattice, const typename SimplexLattice<D>::Cell& cell)
{
    return lattice.h() * Real(1 << cell.log2Size);
}

/// Runs body(cell, slots, perSlot) for every cell, accumulating per-slot D-vectors in
/// @a perSlot (resized here; each block zeroes its own slots), then gathers them per node
/// (deterministic: fixed block order, no atomics).
template <int D, typename CellBody>
void
assemblePerNode(const SimplexLattice<D>& lattice, NodeVectors<D>& out, NodeVectors<D>& perSlot,
                bool threaded, const CellBody& body)
{
    perSlot.resize(D, Eigen::Index(lattice.slotNodes().size()));
    auto blocks = [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const auto& block = lattice.blocks()[b];
            perSlot
                .middleCols(Eigen::Index(block.slotBegin),
                            Eigen::Index(block.slotEnd - block.slotBegin))
                .setZero();
            for (std::size_t ci = block.cellBegin; ci < block.cellEnd; ++ci) {
                const int32_t* slots = lattice.cellSlots().data() + ci * SimplexLattice<D>::CORNERS;
                body(lattice.cells()[ci], slots, perSlot);
            }
        }
    };
    const tbb::blocked_range<std::size_t> range(0, lattice.blocks().size(), 1);
    if (threaded)
        tbb::parallel_for(range, blocks);
    else
        blocks(range);
    lattice.gatherSlots(perSlot, out, threaded);
}

/// Triplets of s^D massWeight M_ref + s^{D-2} stiffWeight L_ref over all cells, rows and
/// columns mapped through @a index (entries with index < 0 dropped).
template <int D>
SparseMatrix
assemble(const SimplexLattice<D>& lattice, Real massWeight, Real stiffWeight,
         const std::vector<int32_t>* index, std::size_t size)
{
    constexpr int C = SimplexLattice<D>::CORNERS;
    const auto& ref = ReferenceCellMatrices<D>::get();
    std::vector<Eigen::Triplet<Real>> triplets;
    std::size_t perCell = 0;
    for (int a = 0; a < C; ++a)
        for (int b = 0; b < C; ++b)
            perCell += comparable(a, b);
    triplets.reserve(lattice.cellCount() * perCell);
    for (const auto& cell : lattice.cells()) {
        const Real s = cellSide(lattice, cell);
        const Real sm = massWeight * std::pow(s, D);
        const Real sl = stiffWeight * std::pow(s, D - 2);
        for (int a = 0; a < C; ++a) {
            const int32_t ia = index ? (*index)[cell.corners[a]] : cell.corners[a];
            if (ia < 0) continue;
            for (int b = 0; b < C; ++b) {
                if (!comparable(a, b)) continue;
                const int32_t ib = index ? (*index)[cell.corners[b]] : cell.corners[b];
                if (ib < 0) continue;
                triplets.emplace_back(ia, ib, sm * ref.mass(a, b) + sl * ref.stiffness(a, b));
            }
        }
    }
    const auto n = Eigen::Index(size);
    SparseMatrix A(n, n);
    A.setFromTriplets(triplets.begin(), triplets.end());
    return A;
}

} // namespace

template <int D>
const ReferenceCellMatrices<D>&
ReferenceCellMatrices<D>::get()
{
    static const ReferenceCellMatrices table = [] {
        ReferenceCellMatrices r;
        r.mass.setZero();
        r.stiffness.setZero();
        const Real volume = 1.0 / factorial<D>();
        // Mass of P1 on a simplex: |T| (1 + delta_ij) / ((D+1)(D+2)).
        const Real m = volume / Real((D + 1) * (D + 2));
        const auto& paths = KuhnSplit<D>::path();
        const auto& axes = KuhnSplit<D>::axis();
        for (std::size_t p = 0; p < paths.size(); ++p) {
            // grad lambda_m = e_{pi(m)} [m >= 1] - e_{pi(m+1)} [m < D] (side 1).
            std::array<Vec<D>, D + 1> grad;
            for (int k = 0; k <= D; ++k) {
                grad[k].setZero();
                if (k >= 1) grad[k][axes[p][k]] += 1;
                if (k < D) grad[k][axes[p][k + 1]] -= 1;
            }
            for (int i = 0; i <= D; ++i)
                for (int j = 0; j <= D; ++j) {
                    const int a = paths[p][i], b = paths[p][j];
                    r.mass(a, b) += m * (i == j ? 2.0 : 1.0);
                    r.stiffness(a, b) += volume * grad[i].dot(grad[j]);
                }
        }
        return r;
    }();
    return table;
}

template <int D>
SparseMatrix
assembleMassMatrix(const SimplexLattice<D>& lattice)
{
    return assemble<D>(lattice, 1.0, 0.0, nullptr, lattice.nodeCount());
}

template <int D>
SparseMatrix
assembleStiffnessMatrix(const SimplexLattice<D>& lattice)
{
    return assemble<D>(lattice, 0.0, 1.0, nullptr, lattice.nodeCount());
}

template <int D>
H1Metric<D>::H1Metric(const SimplexLattice<D>& lattice, Real tau, const H1MetricOptions& opts,
                      bool threaded)
    : mLattice(&lattice), mTau(tau), mOpts(opts)
{
    if (!std::isfinite(tau) || tau < 0)
        OPENVDB_THROW(openvdb::ValueError, "H1Metric: tau must be finite and >= 0, got " << tau);
    const std::size_t n = lattice.nodeCount();
    mUnknown.assign(n, -1);
    mDirichlet.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        if (lattice.isBoundaryNode(i)) {
            mDirichlet[i] = 1;
            continue;
        }
        mSupportNodes.push_back(int32_t(i));
        if (lattice.isHangingNode(i)) continue;
        mUnknown[i] = int32_t(mFreeNodes.size());
        mFreeNodes.push_back(int32_t(i));
    }

    bool direct = false;
    switch (opts.method) {
    case H1MetricOptions::Method::Direct:
        direct = true;
        break;
    case H1MetricOptions::Method::ConjugateGradient:
        direct = false;
        break;
    case H1MetricOptions::Method::Auto:
        direct = unknownCount() <= (D == 2 ? opts.directMaxUnknowns2D : opts.directMaxUnknowns3D);
        break;
    }

    if (direct) {
        if (unknownCount() == 0) return;
        mFactor = std::make_unique<Factor>();
        mFactor->compute(matrix());
        if (mFactor->info() != Eigen::Success)
            OPENVDB_THROW(openvdb::ValueError, "H1Metric: the factorisation of M + tau L failed ("
                                                   << unknownCount() << " unknowns)");
        return;
    }

    // Jacobi preconditioner: the diagonal of G, per node.
    const auto& ref = ReferenceCellMatrices<D>::get();
    NodeVectors<D> diag, perSlot;
    assemblePerNode<D>(lattice, diag, perSlot, threaded,
                       [&](const typename SimplexLattice<D>::Cell& cell, const int32_t* slots,
                           NodeVectors<D>& acc) {
                           const Real s = cellSide(lattice, cell);
                           const Real sm = std::pow(s, D), sl = mTau * std::pow(s, D - 2);
                           for (int a = 0; a < SimplexLattice<D>::CORNERS; ++a)
                               acc.col(slots[a]).array() +=
                                   sm * ref.mass(a, a) + sl * ref.stiffness(a, a);
                       });
    // Constrained space: diag(P^T G P) approximated by diag(G) on the free nodes plus
    // w^2 G_hh from each hanging node h onto each of its masters m (weight w). Positive, so the
    // preconditioner is SPD; the cross terms 2 w G_hm are left out.
    const auto& hanging = lattice.hangingNodes();
    for (std::size_t k = 0; k < hanging.size(); ++k) {
        const auto hn = std::size_t(hanging[k]);
        if (mDirichlet[hn]) continue;
        for (std::size_t j = lattice.constraintOffsets()[k]; j < lattice.constraintOffsets()[k + 1];
             ++j) {
            const Real w = lattice.constraintWeights()[j];
            diag(0, lattice.constraintMasters()[j]) += w * w * diag(0, hn);
        }
    }
    mInverseDiagonal.setZero(Eigen::Index(n));
    for (std::size_t i = 0; i < n; ++i)
        if (mUnknown[i] >= 0) mInverseDiagonal[i] = 1.0 / diag(0, i);
}

template <int D> H1Metric<D>::~H1Metric() = default;

template <int D>
SparseMatrix
H1Metric<D>::matrix() const
{
    const auto& L = *mLattice;
    if (L.hangingNodeCount() == 0) return assemble<D>(L, 1.0, mTau, &mUnknown, unknownCount());
    // P^T G P with G on every node and P: free unknowns -> nodes (identity on the free nodes,
    // the resolved constraints on the non-Dirichlet hanging nodes, 0 on the Dirichlet nodes).
    const SparseMatrix G = assemble<D>(L, 1.0, mTau, nullptr, L.nodeCount());
    std::vector<Eigen::Triplet<Real>> triplets;
    triplets.reserve(mFreeNodes.size() + L.constraintMasters().size());
    for (std::size_t k = 0; k < mFreeNodes.size(); ++k)
        triplets.emplace_back(mFreeNodes[k], int32_t(k), 1.0);
    const auto& hanging = L.hangingNodes();
    for (std::size_t k = 0; k < hanging.size(); ++k) {
        if (mDirichlet[std::size_t(hanging[k])]) continue;
        for (std::size_t j = L.constraintOffsets()[k]; j < L.constraintOffsets()[k + 1]; ++j) {
            const int32_t m = mUnknown[std::size_t(L.constraintMasters()[j])];
            if (m >= 0) triplets.emplace_back(hanging[k], m, L.constraintWeights()[j]);
        }
    }
    SparseMatrix P(Eigen::Index(L.nodeCount()), Eigen::Index(unknownCount()));
    P.setFromTriplets(triplets.begin(), triplets.end());
    const SparseMatrix GP = G * P;
    SparseMatrix A = SparseMatrix(P.transpose()) * GP;
    // Exactly symmetric (the two products round differently).
    A = 0.5 * (A + SparseMatrix(A.transpose()));
    return A;
}

template <int D>
void
H1Metric<D>::zeroDirichlet(NodeVectors<D>& v) const
{
    for (std::size_t i = 0; i < mDirichlet.size(); ++i)
        if (mDirichlet[i]) v.col(i).setZero();
}

template <int D>
void
H1Metric<D>::project(NodeVectors<D>& v) const
{
    zeroDirichlet(v);
    mLattice->expand(v);
}

template <int D>
Real
H1Metric<D>::pairing(const NodeVectors<D>& g, const NodeVectors<D>& v) const
{
    Real sum = 0;
    for (int32_t i : mSupportNodes)
        sum += g.col(i).dot(v.col(i));
    return sum;
}

template <int D>
void
H1Metric<D>::apply(const NodeVectors<D>& v, NodeVectors<D>& out, bool threaded) const
{
    NodeVectors<D> perSlot, expanded;
    apply(v, out, perSlot, expanded, threaded);
}

template <int D>
void
H1Metric<D>::apply(const NodeVectors<D>& vIn, NodeVectors<D>& out, NodeVectors<D>& perSlot,
                   NodeVectors<D>& expanded, bool threaded) const
{
    const bool hasHanging = mLattice->hangingNodeCount() > 0;
    if (hasHanging) {
        // P v: the free values of v, interpolated at the hanging nodes.
        expanded = vIn;
        project(expanded);
    }
    const NodeVectors<D>& v = hasHanging ? expanded : vIn;
    constexpr int C = SimplexLattice<D>::CORNERS;
    using CellMatrix = typename ReferenceCellMatrices<D>::Matrix;
    const auto& ref = ReferenceCellMatrices<D>::get();
    const auto& L = *mLattice;
    // The cell matrix depends only on the cell size: one per log2Size.
    int maxLog2Size = 0;
    for (const auto& cell : L.cells())
        maxLog2Size = std::max(maxLog2Size, cell.log2Size);
    std::vector<CellMatrix> K(std::size_t(maxLog2Size) + 1);
    for (int s = 0; s <= maxLog2Size; ++s) {
        const Real side = L.h() * Real(1 << s);
        K[s] = std::pow(side, D) * ref.mass + mTau * std::pow(side, D - 2) * ref.stiffness;
    }
    assemblePerNode<D>(L, out, perSlot, threaded,
                       [&](const typename SimplexLattice<D>::Cell& cell, const int32_t* slots,
                           NodeVectors<D>& acc) {
                           Eigen::Matrix<Real, D, C> local;
                           for (int a = 0; a < C; ++a) {
                               const int32_t node = cell.corners[a];
                               if (!mDirichlet[node])
                                   local.col(a) = v.col(node);
                               else
                                   local.col(a).setZero();
                           }
                           const Eigen::Matrix<Real, D, C> product = local * K[cell.log2Size];
                           for (int a = 0; a < C; ++a)
                               acc.col(slots[a]) += product.col(a);
                       });
    // P^T (G P v), restricted to the free nodes.
    if (hasHanging) mLattice->reduce(out);
    zeroDirichlet(out);
}

template <int D>
MetricSolveInfo
H1Metric<D>::applyInverse(const NodeVectors<D>& gIn, NodeVectors<D>& out, bool threaded,
                          const NodeVectors<D>* initialGuess) const
{
    const std::size_t n = mLattice->nodeCount();
    if (std::size_t(gIn.cols()) != n)
        OPENVDB_THROW(openvdb::ValueError, "H1Metric::applyInverse: expected "
                                               << n << " node values, got " << gIn.cols());
    const bool warm = initialGuess && !mFactor && initialGuess->rows() == D &&
                      std::size_t(initialGuess->cols()) == n;
    if (warm) {
        if (initialGuess != &out) out = *initialGuess;
    } else {
        out.setZero(D, Eigen::Index(n));
    }
    if (unknownCount() == 0) return {};
    // P^T g: the hanging nodes' co-vector entries moved to their masters.
    const bool hasHanging = mLattice->hangingNodeCount() > 0;
    NodeVectors<D> reduced;
    if (hasHanging) {
        reduced = gIn;
        zeroDirichlet(reduced);
        mLattice->reduce(reduced);
    }
    const NodeVectors<D>& g = hasHanging ? reduced : gIn;
    MetricSolveInfo info;
    if (!mFactor) {
        info = solveCg(g, out, threaded, warm);
    } else {
        // All D components with one factorisation: right-hand sides as the columns of B.
        Eigen::Matrix<Real, Eigen::Dynamic, D> B(Eigen::Index(unknownCount()), D);
        for (std::size_t k = 0; k < mFreeNodes.size(); ++k)
            B.row(Eigen::Index(k)) = g.col(mFreeNodes[k]).transpose();
        const Eigen::Matrix<Real, Eigen::Dynamic, D> X = mFactor->solve(B);
        for (std::size_t k = 0; k < mFreeNodes.size(); ++k)
            out.col(mFreeNodes[k]) = X.row(Eigen::Index(k)).transpose();
    }
    // P x: interpolated at the hanging nodes (0 at the Dirichlet nodes).
    if (hasHanging) project(out);
    return info;
}

template <int D>
MetricSolveInfo
H1Metric<D>::solveCg(const NodeVectors<D>& g, NodeVectors<D>& x, bool threaded, bool warm) const
{
    // Jacobi-preconditioned CG, the D components iterated together (one operator application
    // per iteration serves all of them); a converged component is frozen. The vector updates
    // are fused into two passes over the nodes, in parallel over fixed chunks whose partial sums
    // are added in chunk order (independent of the thread count).
    using Col = Vec<D>;
    const Eigen::Index n = x.cols();
    const Eigen::Index chunks = (n + CG_CHUNK - 1) / CG_CHUNK;
    std::vector<Eigen::Matrix<Real, D, 3>> partial(static_cast<std::size_t>(chunks));
    // Runs body(begin, end, partialSums) per chunk; returns the D x 3 sums in chunk order.
    auto pass = [&](const auto& body) {
        auto run = [&](const tbb::blocked_range<Eigen::Index>& r) {
            for (Eigen::Index c = r.begin(); c != r.end(); ++c) {
                partial[c].setZero();
                body(c * CG_CHUNK, std::min(n, (c + 1) * CG_CHUNK), partial[c]);
            }
        };
        const tbb::blocked_range<Eigen::Index> range(0, chunks, 1);
        if (threaded)
            tbb::parallel_for(range, run);
        else
            run(range);
        Eigen::Matrix<Real, D, 3> sum = Eigen::Matrix<Real, D, 3>::Zero();
        for (const auto& p : partial)
            sum += p;
        return sum;
    };
    const auto& invDiag = mInverseDiagonal;
    NodeVectors<D> r(D, n), z(D, n), p(D, n), q, perSlot, expanded;
    // |b|: the norm of g on the free nodes (the tolerance is relative to it, warm or not).
    const Col bNorm = pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>& acc) {
                          for (Eigen::Index i = b; i < e; ++i)
                              if (invDiag[i] != 0) acc.col(0) += g.col(i).cwiseProduct(g.col(i));
                      })
                          .col(0)
                          .cwiseSqrt();
    // Warm start: x0 = the guess on the free nodes (0 elsewhere, and in a component whose
    // right-hand side is 0), q = A x0 (G acts on each component separately).
    if (warm) {
        Col keep;
        for (int c = 0; c < D; ++c)
            keep[c] = bNorm[c] > 0 ? 1.0 : 0.0;
        pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>&) {
            for (Eigen::Index i = b; i < e; ++i) {
                if (invDiag[i] == 0)
                    x.col(i).setZero();
                else
                    x.col(i) = x.col(i).cwiseProduct(keep);
            }
        });
        apply(x, q, perSlot, expanded, threaded);
    }
    // r = g - A x0 (Dirichlet entries 0), z = p = D^{-1} r; sums: |r|^2, r.z
    auto sums = pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>& acc) {
        for (Eigen::Index i = b; i < e; ++i) {
            r.col(i) = invDiag[i] != 0 ? Col(g.col(i)) : Col::Zero();
            if (warm && invDiag[i] != 0) r.col(i) -= q.col(i);
            z.col(i) = invDiag[i] * r.col(i);
            p.col(i) = z.col(i);
            acc.col(0) += r.col(i).cwiseProduct(r.col(i));
            acc.col(1) += r.col(i).cwiseProduct(z.col(i));
        }
    });
    Col rNorm = sums.col(0).cwiseSqrt(), rz = sums.col(1);
    MetricSolveInfo info;
    auto done = [&](int c) { return !(rNorm[c] > mOpts.cgTolerance * bNorm[c]); };
    auto allDone = [&] {
        for (int c = 0; c < D; ++c)
            if (!done(c)) return false;
        return true;
    };
    while (!allDone() && info.iterations < mOpts.cgMaxIterations) {
        apply(p, q, perSlot, expanded, threaded);
        const Col pq = pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>& acc) {
                           for (Eigen::Index i = b; i < e; ++i)
                               acc.col(0) += p.col(i).cwiseProduct(q.col(i));
                       }).col(0);
        Col alpha;
        for (int c = 0; c < D; ++c)
            alpha[c] = done(c) || !(pq[c] > 0) ? 0.0 : rz[c] / pq[c];
        sums = pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>& acc) {
            for (Eigen::Index i = b; i < e; ++i) {
                x.col(i) += alpha.cwiseProduct(p.col(i));
                r.col(i) -= alpha.cwiseProduct(q.col(i));
                z.col(i) = invDiag[i] * r.col(i);
                acc.col(0) += r.col(i).cwiseProduct(r.col(i));
                acc.col(1) += r.col(i).cwiseProduct(z.col(i));
            }
        });
        rNorm = sums.col(0).cwiseSqrt();
        Col beta;
        for (int c = 0; c < D; ++c)
            beta[c] = rz[c] > 0 ? sums(c, 1) / rz[c] : 0.0;
        rz = sums.col(1);
        pass([&](Eigen::Index b, Eigen::Index e, Eigen::Matrix<Real, D, 3>&) {
            for (Eigen::Index i = b; i < e; ++i)
                p.col(i) = z.col(i) + beta.cwiseProduct(p.col(i));
        });
        ++info.iterations;
    }
    info.converged = allDone();
    for (int c = 0; c < D; ++c)
        if (bNorm[c] > 0)
            info.relativeResidual = std::max(info.relativeResidual, rNorm[c] / bNorm[c]);
    return info;
}

template class H1Metric<2>;
template class H1Metric<3>;
template struct ReferenceCellMatrices<2>;
template struct ReferenceCellMatrices<3>;
template SparseMatrix assembleMassMatrix<2>(const SimplexLattice<2>&);
template SparseMatrix assembleMassMatrix<3>(const SimplexLattice<3>&);
template SparseMatrix assembleStiffnessMatrix<2>(const SimplexLattice<2>&);
template SparseMatrix assembleStiffnessMatrix<3>(const SimplexLattice<3>&);

} // namespace solver
} // namespace vdbmatch
