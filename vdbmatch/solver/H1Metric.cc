/// @file H1Metric.cc
#include "H1Metric.h"

#include <vdbmatch/Parallel.h>

#include <openvdb/Exceptions.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <utility>

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

    assemble(threaded);
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
    // Jacobi preconditioner: the exact diagonal of P^T G P (positive: G is SPD, P injective).
    mInverseDiagonal.setZero(Eigen::Index(unknownCount()));
    for (std::size_t i = 0; i < unknownCount(); ++i)
        for (std::size_t k = mRowBegin[i]; k < mRowBegin[i + 1]; ++k)
            if (mColumns[k] == int32_t(i)) mInverseDiagonal[Eigen::Index(i)] = 1.0 / mValues[k];
}

template <int D>
void
H1Metric<D>::assemble(bool threaded)
{
    // Row i of P^T G P is sum over the nodes n with P_ni = w != 0 (the free node itself, w = 1,
    // and the non-Dirichlet hanging nodes it masters) of w G_nm P_mj over the cells around n.
    // Rows are built independently, each in a fixed order, then stored in row order.
    constexpr int C = SimplexLattice<D>::CORNERS;
    using CellMatrix = typename ReferenceCellMatrices<D>::Matrix;
    const auto& L = *mLattice;
    const auto& ref = ReferenceCellMatrices<D>::get();
    const std::size_t n = L.nodeCount(), unknowns = unknownCount();

    // The cell matrix depends only on the cell size: one per log2Size.
    int maxLog2Size = 0;
    for (const auto& cell : L.cells())
        maxLog2Size = std::max(maxLog2Size, cell.log2Size);
    std::vector<CellMatrix> K(std::size_t(maxLog2Size) + 1);
    for (int s = 0; s <= maxLog2Size; ++s) {
        const Real side = L.h() * Real(1 << s);
        K[std::size_t(s)] =
            std::pow(side, D) * ref.mass + mTau * std::pow(side, D - 2) * ref.stiffness;
    }
    // (cell, corner) pairs around each node, CSR.
    std::vector<std::size_t> aroundBegin(n + 1, 0);
    for (const auto& cell : L.cells())
        for (int a = 0; a < C; ++a)
            ++aroundBegin[std::size_t(cell.corners[a]) + 1];
    for (std::size_t i = 0; i < n; ++i)
        aroundBegin[i + 1] += aroundBegin[i];
    std::vector<int32_t> around(aroundBegin[n]);
    {
        std::vector<std::size_t> next(aroundBegin.begin(), aroundBegin.end() - 1);
        for (std::size_t ci = 0; ci < L.cellCount(); ++ci)
            for (int a = 0; a < C; ++a)
                around[next[std::size_t(L.cells()[ci].corners[a])]++] = int32_t(ci * C + a);
    }
    // P row by row: node -> (unknown, weight) list, CSR (empty for the Dirichlet nodes).
    std::vector<std::size_t> pBegin(n + 1, 0);
    std::vector<int32_t> pUnknown;
    std::vector<Real> pWeight;
    pUnknown.reserve(n);
    pWeight.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
        if (mUnknown[i] >= 0) {
            pUnknown.push_back(mUnknown[i]);
            pWeight.push_back(1.0);
        } else if (!mDirichlet[i] && L.isHangingNode(i)) {
            const auto k = std::size_t(L.hangingIndex(i));
            for (std::size_t j = L.constraintOffsets()[k]; j < L.constraintOffsets()[k + 1]; ++j) {
                const int32_t m = mUnknown[std::size_t(L.constraintMasters()[j])];
                if (m < 0) continue;
                pUnknown.push_back(m);
                pWeight.push_back(L.constraintWeights()[j]);
            }
        }
        pBegin[i + 1] = pUnknown.size();
    }
    // P^T by columns: unknown -> (node, weight), the transpose of the lists above.
    std::vector<std::size_t> tBegin(unknowns + 1, 0);
    for (int32_t u : pUnknown)
        ++tBegin[std::size_t(u) + 1];
    for (std::size_t i = 0; i < unknowns; ++i)
        tBegin[i + 1] += tBegin[i];
    std::vector<int32_t> tNode(pUnknown.size());
    std::vector<Real> tWeight(pUnknown.size());
    {
        std::vector<std::size_t> next(tBegin.begin(), tBegin.end() - 1);
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t k = pBegin[i]; k < pBegin[i + 1]; ++k) {
                const std::size_t slot = next[std::size_t(pUnknown[k])]++;
                tNode[slot] = int32_t(i);
                tWeight[slot] = pWeight[k];
            }
    }

    // Rows in fixed chunks; each chunk keeps its entries, then they are concatenated.
    constexpr std::size_t ROWS_PER_CHUNK = 2048;
    const std::size_t chunks = (unknowns + ROWS_PER_CHUNK - 1) / ROWS_PER_CHUNK;
    std::vector<std::vector<int32_t>> chunkColumns(chunks);
    std::vector<std::vector<Real>> chunkValues(chunks);
    std::vector<std::size_t> rowLength(unknowns, 0);
    detail::forEachIndex(chunks, threaded, [&](std::size_t c) {
        // The row's (column, sum) pairs, in order of first appearance (a row has at most a few
        // dozen columns: a linear search beats a map).
        std::vector<std::pair<int32_t, Real>> rowEntries;
        auto add = [&](int32_t col, Real value) {
            for (auto& [column, sum] : rowEntries)
                if (column == col) {
                    sum += value;
                    return;
                }
            rowEntries.emplace_back(col, value);
        };
        auto& cols = chunkColumns[c];
        auto& vals = chunkValues[c];
        // 15 columns per row on a uniform 3D lattice, more next to hanging nodes.
        cols.reserve(ROWS_PER_CHUNK * (D == 3 ? 20 : 8));
        vals.reserve(ROWS_PER_CHUNK * (D == 3 ? 20 : 8));
        const std::size_t end = std::min(unknowns, (c + 1) * ROWS_PER_CHUNK);
        for (std::size_t row = c * ROWS_PER_CHUNK; row < end; ++row) {
            rowEntries.clear();
            for (std::size_t t = tBegin[row]; t < tBegin[row + 1]; ++t) {
                const auto node = std::size_t(tNode[t]);
                const Real w = tWeight[t];
                for (std::size_t q = aroundBegin[node]; q < aroundBegin[node + 1]; ++q) {
                    const std::size_t ci = std::size_t(around[q]) / C;
                    const int a = around[q] % C;
                    const auto& cell = L.cells()[ci];
                    const CellMatrix& Kc = K[std::size_t(cell.log2Size)];
                    for (int b = 0; b < C; ++b) {
                        if (!comparable(a, b)) continue;
                        const auto m = std::size_t(cell.corners[b]);
                        const Real wk = w * Kc(a, b);
                        for (std::size_t k = pBegin[m]; k < pBegin[m + 1]; ++k)
                            add(pUnknown[k], wk * pWeight[k]);
                    }
                }
            }
            // Sorted by column; equal columns summed in the order of generation.
            std::sort(rowEntries.begin(), rowEntries.end());
            std::size_t length = 0;
            for (const auto& [col, sum] : rowEntries) {
                cols.push_back(col);
                vals.push_back(sum);
                ++length;
            }
            rowLength[row] = length;
        }
    });
    mRowBegin.assign(unknowns + 1, 0);
    for (std::size_t i = 0; i < unknowns; ++i)
        mRowBegin[i + 1] = mRowBegin[i] + rowLength[i];
    mColumns.resize(mRowBegin[unknowns]);
    mValues.resize(mRowBegin[unknowns]);
    detail::forEachIndex(chunks, threaded, [&](std::size_t c) {
        const std::size_t begin = mRowBegin[c * ROWS_PER_CHUNK];
        std::copy(chunkColumns[c].begin(), chunkColumns[c].end(),
                  mColumns.begin() + std::ptrdiff_t(begin));
        std::copy(chunkValues[c].begin(), chunkValues[c].end(),
                  mValues.begin() + std::ptrdiff_t(begin));
    });
}

template <int D> H1Metric<D>::~H1Metric() = default;

template <int D>
SparseMatrix
H1Metric<D>::matrix() const
{
    const auto n = Eigen::Index(unknownCount());
    std::vector<Eigen::Triplet<Real>> triplets;
    triplets.reserve(mColumns.size());
    for (std::size_t i = 0; i < unknownCount(); ++i)
        for (std::size_t k = mRowBegin[i]; k < mRowBegin[i + 1]; ++k)
            triplets.emplace_back(int32_t(i), mColumns[k], mValues[k]);
    SparseMatrix A(n, n);
    A.setFromTriplets(triplets.begin(), triplets.end());
    // Exactly symmetric (entries ij and ji are summed in different orders).
    A = 0.5 * (A + SparseMatrix(A.transpose()));
    return A;
}

template <int D>
void
H1Metric<D>::multiply(const NodeVectors<D>& x, NodeVectors<D>& y, bool threaded) const
{
    y.resize(D, x.cols());
    detail::forEachIndex((unknownCount() + CG_CHUNK - 1) / CG_CHUNK, threaded, [&](std::size_t c) {
        const std::size_t end = std::min(unknownCount(), (c + 1) * std::size_t(CG_CHUNK));
        for (std::size_t i = c * std::size_t(CG_CHUNK); i < end; ++i) {
            Vec<D> sum = Vec<D>::Zero();
            for (std::size_t k = mRowBegin[i]; k < mRowBegin[i + 1]; ++k)
                sum += mValues[k] * x.col(mColumns[k]);
            y.col(Eigen::Index(i)) = sum;
        }
    });
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
    const auto u = Eigen::Index(unknownCount());
    NodeVectors<D> x(D, u), y;
    for (Eigen::Index k = 0; k < u; ++k)
        x.col(k) = v.col(mFreeNodes[std::size_t(k)]);
    multiply(x, y, threaded);
    out.setZero(D, v.cols());
    for (Eigen::Index k = 0; k < u; ++k)
        out.col(mFreeNodes[std::size_t(k)]) = y.col(k);
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
    const auto u = Eigen::Index(unknownCount());
    typename detail::ScratchBuffer<Workspace>::Lease lease(mWorkspace);
    Workspace& w = *lease;
    NodeVectors<D>& x = w.x;
    x.resize(D, u);
    if (warm) {
        for (Eigen::Index k = 0; k < u; ++k)
            x.col(k) = initialGuess->col(mFreeNodes[std::size_t(k)]);
    }
    out.setZero(D, Eigen::Index(n));
    if (u == 0) return {};
    // b = P^T g on the unknowns: the hanging nodes' co-vector entries moved to their masters.
    NodeVectors<D>& b = w.b;
    b.resize(D, u);
    if (mLattice->hangingNodeCount() > 0) {
        NodeVectors<D>& reduced = w.reduced;
        reduced = gIn;
        zeroDirichlet(reduced);
        mLattice->reduce(reduced);
        for (Eigen::Index k = 0; k < u; ++k)
            b.col(k) = reduced.col(mFreeNodes[std::size_t(k)]);
    } else {
        for (Eigen::Index k = 0; k < u; ++k)
            b.col(k) = gIn.col(mFreeNodes[std::size_t(k)]);
    }
    MetricSolveInfo info;
    if (!mFactor) {
        info = solveCg(b, x, w, threaded, warm);
    } else {
        // All D components with one factorisation. Eigen's triangular solves treat the columns
        // of a right-hand side one after the other with the same arithmetic, so solving them
        // side by side (one component per task) gives the same bits as one multi-column solve.
        auto solveComponent = [&](int c) {
            const Eigen::Matrix<Real, Eigen::Dynamic, 1> xc = mFactor->solve(b.row(c).transpose());
            x.row(c) = xc.transpose();
        };
        if (threaded) {
            tbb::parallel_for(0, D, solveComponent);
        } else {
            for (int c = 0; c < D; ++c)
                solveComponent(c);
        }
    }
    for (Eigen::Index k = 0; k < u; ++k)
        out.col(mFreeNodes[std::size_t(k)]) = x.col(k);
    // P x: interpolated at the hanging nodes (0 at the Dirichlet nodes).
    if (mLattice->hangingNodeCount() > 0) project(out);
    return info;
}

template <int D>
MetricSolveInfo
H1Metric<D>::solveCg(const NodeVectors<D>& b, NodeVectors<D>& x, Workspace& w, bool threaded,
                     bool warm) const
{
    // Jacobi-preconditioned CG, the D components iterated together (one product per iteration
    // serves all of them); a converged component is frozen. The vector updates are fused into
    // passes over the unknowns, in parallel over fixed chunks whose partial sums are added in
    // chunk order (independent of the thread count).
    using Col = Vec<D>;
    const Eigen::Index n = Eigen::Index(unknownCount());
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
    // q.col(i) = (A v).col(i) for i in [begin, end).
    auto product = [&](const NodeVectors<D>& v, NodeVectors<D>& q, Eigen::Index begin,
                       Eigen::Index end) {
        for (Eigen::Index i = begin; i < end; ++i) {
            Col sum = Col::Zero();
            for (std::size_t k = mRowBegin[std::size_t(i)]; k < mRowBegin[std::size_t(i) + 1]; ++k)
                sum += mValues[k] * v.col(mColumns[k]);
            q.col(i) = sum;
        }
    };
    const auto& invDiag = mInverseDiagonal;
    NodeVectors<D>&r = w.r, &z = w.z, &p = w.p, &q = w.q;
    for (NodeVectors<D>* v : {&r, &z, &p, &q})
        v->resize(D, n);
    // |b|: the tolerance is relative to it, warm or not.
    const Col bNorm = pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>& acc) {
                          for (Eigen::Index i = i0; i < i1; ++i)
                              acc.col(0) += b.col(i).cwiseProduct(b.col(i));
                      })
                          .col(0)
                          .cwiseSqrt();
    // Warm start: x0 = the guess (0 in a component whose right-hand side is 0), q = A x0 (A acts
    // on each component separately).
    if (warm) {
        Col keep;
        for (int c = 0; c < D; ++c)
            keep[c] = bNorm[c] > 0 ? 1.0 : 0.0;
        pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>&) {
            for (Eigen::Index i = i0; i < i1; ++i)
                x.col(i) = x.col(i).cwiseProduct(keep);
        });
        pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>&) {
            product(x, q, i0, i1);
        });
    } else {
        x.setZero(D, n);
    }
    // r = b - A x0, z = p = D^{-1} r; sums: |r|^2, r.z
    auto sums = pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>& acc) {
        for (Eigen::Index i = i0; i < i1; ++i) {
            r.col(i) = b.col(i);
            if (warm) r.col(i) -= q.col(i);
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
        // q = A p and p.q in one pass.
        const Col pq = pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>& acc) {
                           product(p, q, i0, i1);
                           for (Eigen::Index i = i0; i < i1; ++i)
                               acc.col(0) += p.col(i).cwiseProduct(q.col(i));
                       }).col(0);
        Col alpha;
        for (int c = 0; c < D; ++c)
            alpha[c] = done(c) || !(pq[c] > 0) ? 0.0 : rz[c] / pq[c];
        sums = pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>& acc) {
            for (Eigen::Index i = i0; i < i1; ++i) {
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
        pass([&](Eigen::Index i0, Eigen::Index i1, Eigen::Matrix<Real, D, 3>&) {
            for (Eigen::Index i = i0; i < i1; ++i)
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
