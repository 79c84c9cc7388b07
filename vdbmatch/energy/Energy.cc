/// @file Energy.cc
#include "Energy.h"

#include <vdbmatch/CpuClones.h>
#include <vdbmatch/energy/CellBandTerms.h>
#include <vdbmatch/energy/CellKinematics.h>
#include <vdbmatch/energy/VolumeTerm.h>
#include <vdbmatch/geometry/BandWeight.h>

#include <openvdb/Exceptions.h>
#include <openvdb/thread/Threading.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <vector>

namespace vdbmatch {

Real
EnergyTerms::total() const
{
    if (invertedSimplices > 0) return INF;
    return match[0] + match[1] + mem[0] + mem[1] + bend[0] + bend[1] + vol[0] + vol[1] + landmark +
           innerDistance;
}

EnergyTerms&
EnergyTerms::operator+=(const EnergyTerms& o)
{
    for (int i = 0; i < 2; ++i) {
        match[i] += o.match[i];
        mem[i] += o.mem[i];
        bend[i] += o.bend[i];
        vol[i] += o.vol[i];
    }
    landmark += o.landmark;
    innerDistance += o.innerDistance;
    invertedSimplices += o.invertedSimplices;
    bandSimplices += o.bandSimplices;
    coarseBandSimplices += o.coarseBandSimplices;
    return *this;
}

namespace {

[[noreturn]] void
throwOutside(const char* which, const Real* x, int d)
{
    std::ostringstream os;
    for (int a = 0; a < d; ++a)
        os << (a ? ", " : "") << x[a];
    OPENVDB_THROW(openvdb::ValueError, "Energy: the fields of "
                                           << which << " do not cover the point (" << os.str()
                                           << "); extend the signed distance grid");
}

} // namespace

template <int D>
Energy<D>::Energy(const SimplexLattice<D>& lattice, const FieldSampler<D>& shape1,
                  const FieldSampler<D>& shape2, const EnergyParameters& params, EnergyKind kind,
                  Real sigma)
    : mLattice(&lattice), mShape1(&shape1), mShape2(&shape2), mParams(params), mKind(kind)
{
    mParams.validate();
    mSigma = sigma > 0 ? sigma : mParams.sigmaFactor * lattice.h();
    mMatchWeight = mParams.cMatch * std::pow(mSigma, -mParams.q);
    mVolumeWeight = mParams.cVol * std::pow(mSigma, mParams.theta);
    cacheSourceGeometry();
}

namespace {

template <int D>
void
packSym(const Mat<D>& M, Eigen::Matrix<Real, D*(D + 1) / 2, 1>& out)
{
    int k = 0;
    for (int i = 0; i < D; ++i)
        for (int j = i; j < D; ++j)
            out[k++] = M(i, j);
}

template <int D>
void
unpackSym(const Eigen::Matrix<Real, D*(D + 1) / 2, 1>& in, Mat<D>& M)
{
    int k = 0;
    for (int i = 0; i < D; ++i)
        for (int j = i; j < D; ++j)
            M(i, j) = M(j, i) = in[k++];
}

/// Lane @a q of the band terms: simplex @a p of the cell (its kinematics and the volume term's
/// gradient), the frame of shape 1 at its centroid, the raw fields of shape 2 at its deformed
/// centroid, and the band weights (eta1 only in the band of M1, as the cache says; eta2 only for
/// the symmetric energy).
template <int D, bool Grad>
void
fillBandLane(energy::CellBandTerms<D>& bt, int q, const energy::CellKinematics<D>& ck, int p,
             const kinematics::SurfaceFrame<D>& f1, const RawFields<D>& raw2,
             const RawFieldDerivatives<D>& deriv2, bool inBand1, bool symmetric,
             const BandWeight& band)
{
    for (int i = 0; i < D; ++i) {
        bt.n1[i][q] = f1.n[i];
        bt.rawN2[i][q] = raw2.n[i];
        if constexpr (Grad) bt.dd2[i][q] = deriv2.dd[i];
        for (int j = 0; j < D; ++j) {
            bt.A[i][j][q] = ck.A[i][j][p];
            bt.B[i][j][q] = ck.B[i][j][p];
            bt.P1[i][j][q] = f1.P(i, j);
            bt.Tp1[i][j][q] = f1.Tp(i, j);
            bt.Tm1[i][j][q] = f1.Tm(i, j);
            bt.R2[i][j][q] = raw2.R(i, j);
            if constexpr (Grad) {
                // Only the gradient uses cof A, and only it has the volume term's dA, dB.
                bt.C[i][j][q] = ck.C[i][j][p];
                bt.dA[i][j][q] = ck.dA[i][j][p];
                bt.dB[i][j][q] = ck.dB[i][j][p];
                bt.dn2[i][j][q] = deriv2.dn(i, j);
                for (int k = 0; k < D; ++k)
                    bt.dR2[k][i][j][q] = deriv2.dR[k](i, j);
            }
        }
    }
    bt.J[q] = ck.J[p];
    bt.d1[q] = f1.d;
    bt.d2[q] = raw2.d;
    bt.eta1[q] = inBand1 ? band(f1.d) : 0;
    bt.eta2D[q] = 0;
    bt.eta2[q] = symmetric ? band(raw2.d, bt.eta2D[q]) : 0;
}

} // namespace

template <int D>
Vec<D>
Energy<D>::centroid(std::size_t ci, std::size_t p) const
{
    const auto& cell = mLattice->cells()[ci];
    const Real h = mLattice->h();
    const Real side = h * Real(1 << cell.log2Size);
    const auto& path = KuhnSplit<D>::path()[p];
    Vec<D> x = Vec<D>::Zero(), origin;
    for (int a = 0; a < D; ++a)
        origin[a] = cell.origin[a] * h;
    for (int m = 0; m <= D; ++m)
        for (int a = 0; a < D; ++a)
            if (path[m] & (1 << a)) x[a] += 1.0;
    return origin + x * (side / (D + 1));
}

template <int D>
void
Energy<D>::cacheSourceGeometry()
{
    using Lattice = SimplexLattice<D>;
    const auto& L = *mLattice;
    const BandWeight band(mSigma);
    mSourceIndex.assign(L.simplexCount(), -1);
    // Pass 1, parallel over blocks: which simplices lie in the band of M1.
    std::vector<std::size_t> count(L.blocks().size(), 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, L.blocks().size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b != r.end(); ++b) {
                              const auto& block = L.blocks()[b];
                              for (std::size_t ci = block.cellBegin; ci < block.cellEnd; ++ci)
                                  for (std::size_t p = 0; p < Lattice::SIMPLICES; ++p) {
                                      const Vec<D> x = centroid(ci, p);
                                      Real d1;
                                      if (!mShape1->sampleDistance(x, d1))
                                          throwOutside("shape 1", x.data(), D);
                                      if (band.inBand(d1)) {
                                          mSourceIndex[ci * Lattice::SIMPLICES + p] = 0;
                                          ++count[b];
                                      }
                                  }
                          }
                      });
    // Pass 2: slots in block order, then the frames, in parallel.
    std::vector<std::size_t> offset(count.size() + 1, 0);
    for (std::size_t b = 0; b < count.size(); ++b)
        offset[b + 1] = offset[b] + count[b];
    mSource.resize(offset.back());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, L.blocks().size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          RawFields<D> raw;
                          kinematics::SurfaceFrame<D> f;
                          for (std::size_t b = r.begin(); b != r.end(); ++b) {
                              const auto& block = L.blocks()[b];
                              std::size_t next = offset[b];
                              for (std::size_t ci = block.cellBegin; ci < block.cellEnd; ++ci)
                                  for (std::size_t p = 0; p < Lattice::SIMPLICES; ++p) {
                                      int32_t& index = mSourceIndex[ci * Lattice::SIMPLICES + p];
                                      if (index < 0) continue;
                                      index = int32_t(next);
                                      mShape1->sample(centroid(ci, p), raw, nullptr);
                                      kinematics::makeFrame(raw, f);
                                      SourcePoint& s = mSource[next++];
                                      s.d = f.d;
                                      s.n = f.n;
                                      packSym<D>(f.Tp, s.Tp);
                                      packSym<D>(f.Tm, s.Tm);
                                  }
                          }
                      });
}

template <int D>
void
Energy<D>::sourceFrame(std::size_t simplex, const Vec<D>& x, kinematics::SurfaceFrame<D>& f) const
{
    const int32_t index = mSourceIndex[simplex];
    if (index >= 0) {
        const SourcePoint& s = mSource[index];
        f.d = s.d;
        f.n = s.n;
        f.P = Mat<D>::Identity() - s.n * s.n.transpose();
        unpackSym<D>(s.Tp, f.Tp);
        unpackSym<D>(s.Tm, f.Tm);
    } else {
        RawFields<D> raw;
        if (!mShape1->sample(x, raw, nullptr)) throwOutside("shape 1", x.data(), D);
        kinematics::makeFrame(raw, f);
    }
}

template <int D>
bool
Energy<D>::cellMayReachBand2(const Vec<D>& origin, Real side,
                             const std::array<Vec<D>, SimplexLattice<D>::CORNERS>& uc) const
{
    constexpr int NC = SimplexLattice<D>::CORNERS;
    if (!mCullCells) return true;
    // The deformed corners y_k and their mean: every deformed centroid y_T of the cell is a
    // convex combination of the y_k, so |y_T - ybar| <= R = max_k |y_k - ybar|.
    std::array<Vec<D>, NC> y;
    Vec<D> ybar = Vec<D>::Zero();
    for (int k = 0; k < NC; ++k) {
        for (int a = 0; a < D; ++a)
            y[k][a] = origin[a] + ((k >> a) & 1 ? side : 0.0) + uc[k][a];
        ybar += y[k];
    }
    ybar /= Real(NC);
    Real R2 = 0;
    for (int k = 0; k < NC; ++k)
        R2 = std::max(R2, (y[k] - ybar).squaredNorm());
    Real d2, voxel;
    if (!mShape2->sampleDistance(ybar, d2, &voxel)) return true;
    // The true distance is 1-Lipschitz and each interpolated tier is within a fraction of its
    // voxel of it, so |d2(y_T)| >= |d2(ybar)| - R - CULL_SLACK_VOXELS * voxel.
    return std::abs(d2) < mSigma + std::sqrt(R2) + CULL_SLACK_VOXELS * voxel;
}

template <int D>
inline bool
Energy<D>::inInverseBand(const Vec<D>& y, InverseBandSample* last) const
{
    if (last && last->tier >= 0 && mShape2->sameStencil(y, last->y, last->tier)) {
        // |d2(y)| >= |d2(last.y)| - slope |y - last.y| (same polynomial on the segment); the
        // relative margin covers the rounding of the interpolation.
        const Real bound = Real(last->absD2) - INVERSE_BAND_SLOPE * (y - last->y).norm();
        if (bound >= mSigma * (1 + 1e-9)) return false;
    }
    Real d2;
    int tier = -1;
    if (!mShape2->sampleDistance(y, d2, tier)) throwOutside("shape 2", y.data(), D);
    if (last) {
        const Real absD2 = std::abs(d2);
        float rounded = float(absD2);
        if (Real(rounded) > absD2) rounded = std::nextafter(rounded, 0.0f);
        last->y = y;
        last->absD2 = rounded;
        last->tier = tier;
    }
    return BandWeight(mSigma).inBand(d2);
}

// flatten: the kinematics, densities and frame maps are inlined into the loop over simplices
// (the same operations in the same order, so the same bits; value and gradient ~15% faster,
// docs/performance.md). In 3D the loop also has an x86-64-v3 (AVX2) clone, chosen at load time
// on CPUs that have it (vdbmatch/CpuClones.h): the 3D match takes 4-6% less time; in 2D the
// clone was 2% slower, so 2D keeps the baseline loop. The same bits either way. The body is
// inlined by flatten, not marked always_inline: with always_inline GCC compiled the clone 27%
// slower than the baseline loop.
template <int D>
template <bool Grad>
void __attribute__((flatten))
Energy<D>::evaluateBlock(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& t,
                         NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const
{
    evaluateBlockBody<Grad>(blockIndex, u, t, perSlot, inverseBand);
}

template <int D>
template <bool Grad>
void __attribute__((flatten)) VDBMATCH_X86_64_V3_CLONES
Energy<D>::evaluateBlockClones(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& t,
                               NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const
{
    evaluateBlockBody<Grad>(blockIndex, u, t, perSlot, inverseBand);
}

template <int D>
template <bool Grad>
void
Energy<D>::evaluateBlockBody(std::size_t blockIndex, const NodeVectors<D>& u, EnergyTerms& t,
                             NodeVectors<D>* perSlot, InverseBandSample* inverseBand) const
{
    using namespace energy;
    constexpr int NC = SimplexLattice<D>::CORNERS;
    constexpr Real INV_FACTORIAL = D == 2 ? 0.5 : 1.0 / 6.0;
    const auto& L = *mLattice;
    const auto& block = L.blocks()[blockIndex];
    const auto& paths = KuhnSplit<D>::path();
    const auto& axes = KuhnSplit<D>::axis();
    const BandWeight band(mSigma);
    const bool symmetric = mKind == EnergyKind::Symmetric;
    const Real h = L.h();

    std::array<Vec<D>, NC> uc;
    kinematics::SurfaceFrame<D> f1; // shape 1 at a band simplex's centroid
    RawFields<D> raw2;
    RawFieldDerivatives<D> deriv2;
    // The kinematics and the symmetric volume term of the cell's simplices, lane by lane (the
    // same bits as SimplexKinematics and VolumeTerm.h, CellKinematics.h); the band terms then
    // go simplex by simplex.
    constexpr int NS = SimplexLattice<D>::SIMPLICES;
    CellKinematics<D> ck;
    std::array<Vec<D>, NS> yc;
    std::array<Vec<D>, NS> dyc;
    std::array<bool, NS> banded{};
    CellBandTerms<D> bt;
    std::array<int, NS> lane; // the cell's simplex of each lane of bt
    // Centroid of simplex p of a cell: origin + side * centroidOffset[p] (the same as centroid()).
    std::array<Vec<D>, NS> centroidOffset;
    for (std::size_t p = 0; p < paths.size(); ++p) {
        centroidOffset[p].setZero();
        for (int m = 0; m <= D; ++m)
            for (int a = 0; a < D; ++a)
                if (paths[p][m] & (1 << a)) centroidOffset[p][a] += 1.0;
        centroidOffset[p] /= Real(D + 1);
    }

    for (std::size_t ci = block.cellBegin; ci < block.cellEnd; ++ci) {
        const auto& cell = L.cells()[ci];
        const Real side = h * Real(1 << cell.log2Size);
        const Real invSide = 1.0 / side;
        Real volume = INV_FACTORIAL;
        for (int a = 0; a < D; ++a)
            volume *= side;
        Vec<D> origin;
        for (int a = 0; a < D; ++a)
            origin[a] = cell.origin[a] * h;
        for (int k = 0; k < NC; ++k)
            uc[k] = u.col(cell.corners[k]);
        const int32_t* slots = L.cellSlots().data() + ci * NC;
        const bool mayReachBand2 = symmetric && cellMayReachBand2(origin, side, uc);

        for (int p = 0; p < NS; ++p) {
            const auto& path = paths[p];
            const auto& axis = axes[p];
            // D phi: column pi(m) is e_pi(m) + (phi(v_m) - phi(v_{m-1})) / side (written as
            // the identity plus the difference, as Mat::Identity() and col() += would).
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    ck.A[i][j][p] = i == j ? 1.0 : 0.0;
            Vec<D> ubar = Vec<D>::Zero();
            for (int m = 0; m <= D; ++m) {
                ubar += uc[path[m]];
                if (m > 0)
                    for (int i = 0; i < D; ++i)
                        ck.A[i][axis[m]][p] += (uc[path[m]][i] - uc[path[m - 1]][i]) * invSide;
            }
            const Vec<D> x = origin + side * centroidOffset[p];
            yc[p] = x + ubar / Real(D + 1);
        }
        ck.kinematics();
        if (symmetric)
            ck.template symmetricVolume<Grad>(mVolumeWeight);
        else if constexpr (Grad)
            ck.zeroGradient();

        // The band simplices of the cell fill the lanes of `bt` (their fields sampled one by
        // one); the band terms are then computed lane by lane (CellBandTerms.h).
        bt.count = 0;
        for (int p = 0; p < NS; ++p) {
            banded[p] = false;
            if (!(ck.J[p] > 0)) {
                ++t.invertedSimplices;
                continue;
            }
            if (symmetric) {
                t.vol[0] += volume * ck.volumeDirect[p];
                t.vol[1] += volume * ck.volumeInverse[p];
            } else {
                // The directional energy's volume term (eq:EcomparisonVol), simplex by simplex.
                const SimplexKinematics<D> k = ck.simplex(p);
                DensityGradient<D> dg;
                DensityGradient<D>* dgp = Grad ? &dg : nullptr;
                if constexpr (Grad) ck.loadGradient(p, dg);
                t.vol[0] += volume * volumeComparison<D, Grad>(k, mVolumeWeight, dgp);
                if constexpr (Grad) ck.storeGradient(p, dg);
            }
            const std::size_t simplex = ci * NS + p;
            const Vec<D>& y = yc[p];
            // Band membership: eta1 from the cache (fixed), eta2 from d2(y) (the symmetric
            // energy only). Shape 2 is sampled in full, with derivatives, only where a band term
            // is active.
            const bool inBand1 = mSourceIndex[simplex] >= 0;
            bool inBand2 = false;
            if (mayReachBand2 && !inBand1)
                inBand2 = inInverseBand(y, inverseBand ? inverseBand + simplex : nullptr);
            if (!(inBand1 || inBand2)) continue;
            banded[p] = true;
            ++t.bandSimplices;
            if (cell.log2Size > 0) ++t.coarseBandSimplices;
            if (!mShape2->sample(y, raw2, Grad ? &deriv2 : nullptr))
                throwOutside("shape 2", y.data(), D);
            sourceFrame(simplex, origin + side * centroidOffset[p], f1);
            const int q = bt.count++;
            lane[q] = p;
            fillBandLane<D, Grad>(bt, q, ck, p, f1, raw2, deriv2, inBand1, symmetric, band);
        }
        bt.frame();
        bt.template terms<Grad>(mMatchWeight, mParams.cMem, mParams.cBend, symmetric,
                                mParams.membraneSaturation);
        if constexpr (Grad) bt.adjoint();
        for (int q = 0; q < bt.count; ++q) {
            if (bt.eta1[q] > 0) {
                t.match[0] += volume * bt.matchDirect[q];
                t.mem[0] += volume * bt.memDirect[q];
                t.bend[0] += volume * bt.bendDirect[q];
            }
            if (bt.eta2[q] > 0) {
                t.match[1] += volume * bt.matchInverse[q];
                t.mem[1] += volume * bt.memInverse[q];
                t.bend[1] += volume * bt.bendInverse[q];
            }
            if constexpr (Grad) {
                // Lane q's results back to its simplex: dE/dA, dE/dB, dE/dy.
                const int p = lane[q];
                for (int i = 0; i < D; ++i) {
                    dyc[p][i] = bt.dy[i][q];
                    for (int j = 0; j < D; ++j) {
                        ck.dA[i][j][p] = bt.dA[i][j][q];
                        ck.dB[i][j][p] = bt.dB[i][j][q];
                    }
                }
            }
        }
        if constexpr (Grad) {
            ck.finish();
            // Chain rule to the simplex vertices: A.col(pi(m)) = (u_m - u_{m-1})/side,
            // y = x + mean(u_m). Everything is multiplied by |T|.
            auto& G = *perSlot;
            for (int p = 0; p < NS; ++p) {
                if (!(ck.J[p] > 0)) continue;
                const auto& path = paths[p];
                const auto& axis = axes[p];
                // Without a band term dy = 0, and adding +0 changes no slot: a slot starts at
                // +0 and sums of values that are not -0 are never -0.
                if (banded[p]) {
                    const Vec<D> share = (volume / (D + 1)) * dyc[p];
                    for (int m = 0; m <= D; ++m)
                        G.col(slots[path[m]]) += share;
                }
                for (int m = 1; m <= D; ++m) {
                    Vec<D> c;
                    for (int i = 0; i < D; ++i)
                        c[i] = (volume * invSide) * ck.dA[i][axis[m]][p];
                    G.col(slots[path[m]]) += c;
                    G.col(slots[path[m - 1]]) -= c;
                }
            }
        }
    }
}

template <int D>
template <bool Grad>
Real
Energy<D>::evaluate(const NodeVectors<D>& u, NodeVectors<D>* gradient, EnergyTerms* terms,
                    bool threaded, openvdb::util::NullInterrupter* interrupter) const
{
    const auto& L = *mLattice;
    if (std::size_t(u.cols()) != L.nodeCount())
        OPENVDB_THROW(openvdb::ValueError, "Energy: expected " << L.nodeCount()
                                                               << " nodal displacements, got "
                                                               << u.cols());
    std::vector<EnergyTerms> partial(L.blocks().size());
    // Each block zeroes its own slots inside the parallel loop (no serial pass over memory).
    typename detail::ScratchBuffer<NodeVectors<D>>::Lease slotLease(mSlotBuffer);
    NodeVectors<D>& perSlot = *slotLease;
    if constexpr (Grad) perSlot.resize(D, L.slotNodes().size());
    // The kept inverse-band samples, when this evaluation holds them (none yet: every entry
    // says "sample"); the symmetric energy only.
    typename detail::ScratchBuffer<std::vector<InverseBandSample>>::Lease bandLease(
        mInverseBandBuffer);
    InverseBandSample* inverseBand = nullptr;
    if (mKind == EnergyKind::Symmetric && bandLease.reused()) {
        if (bandLease->size() != L.simplexCount()) bandLease->assign(L.simplexCount(), {});
        inverseBand = bandLease->data();
    }
    bool interrupted = false;
    auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        if (interrupter && interrupter->wasInterrupted()) {
            interrupted = true;
            openvdb::thread::cancelGroupExecution();
            return;
        }
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            if constexpr (Grad) {
                const auto& block = L.blocks()[b];
                perSlot.middleCols(block.slotBegin, block.slotEnd - block.slotBegin).setZero();
            }
            if constexpr (D == 3)
                evaluateBlockClones<Grad>(b, u, partial[b], Grad ? &perSlot : nullptr, inverseBand);
            else
                evaluateBlock<Grad>(b, u, partial[b], Grad ? &perSlot : nullptr, inverseBand);
        }
    };
    const tbb::blocked_range<std::size_t> range(0, L.blocks().size(), 1);
    if (threaded)
        tbb::parallel_for(range, body);
    else
        body(range);

    EnergyTerms sum;
    if (!interrupted)
        for (const auto& p : partial)
            sum += p;
    if (interrupted) {
        if (terms) *terms = sum;
        if (gradient) gradient->setZero(D, L.nodeCount());
        return INF;
    }
    if constexpr (Grad) {
        if (std::isfinite(sum.total())) {
            L.gatherSlots(perSlot, *gradient, threaded);
            if (mLandmarks) sum.landmark = mLandmarks->addGradient(u, *gradient);
            if (mInnerDistance) sum.innerDistance = mInnerDistance->addGradient(u, *gradient);
        } else {
            gradient->setZero(D, L.nodeCount());
        }
    } else if (std::isfinite(sum.total())) {
        if (mLandmarks) sum.landmark = mLandmarks->value(u);
        if (mInnerDistance) sum.innerDistance = mInnerDistance->value(u);
    }
    if (terms) *terms = sum;
    return sum.total();
}

template <int D>
Real
Energy<D>::constantOffset() const
{
    if (mKind == EnergyKind::Symmetric) return 0;
    Real volume = 0;
    for (const auto& cell : mLattice->cells()) {
        Real v = 1;
        for (int a = 0; a < D; ++a)
            v *= mLattice->h() * Real(1 << cell.log2Size);
        volume += v;
    }
    return mVolumeWeight * math::volW<D>(Mat<D>::Identity()) * volume;
}

template <int D>
Real
Energy<D>::value(const NodeVectors<D>& u, EnergyTerms* terms, bool threaded,
                 openvdb::util::NullInterrupter* interrupter) const
{
    return evaluate<false>(u, nullptr, terms, threaded, interrupter);
}

template <int D>
Real
Energy<D>::valueAndGradient(const NodeVectors<D>& u, NodeVectors<D>& gradient, EnergyTerms* terms,
                            bool threaded, openvdb::util::NullInterrupter* interrupter) const
{
    return evaluate<true>(u, &gradient, terms, threaded, interrupter);
}

template <int D>
Real
Energy<D>::minJacobianDeterminant(const NodeVectors<D>& u, bool threaded) const
{
    const auto& L = *mLattice;
    std::vector<Real> blockMin(L.blocks().size(), INF);
    auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        const auto& paths = KuhnSplit<D>::path();
        const auto& axes = KuhnSplit<D>::axis();
        for (std::size_t b = r.begin(); b != r.end(); ++b) {
            const auto& block = L.blocks()[b];
            for (std::size_t ci = block.cellBegin; ci < block.cellEnd; ++ci) {
                const auto& cell = L.cells()[ci];
                const Real invSide = 1.0 / (L.h() * Real(1 << cell.log2Size));
                for (std::size_t p = 0; p < paths.size(); ++p) {
                    Mat<D> A = Mat<D>::Identity();
                    for (int m = 1; m <= D; ++m)
                        A.col(axes[p][m]) += (u.col(cell.corners[paths[p][m]]) -
                                              u.col(cell.corners[paths[p][m - 1]])) *
                                             invSide;
                    blockMin[b] = std::min(blockMin[b], A.determinant());
                }
            }
        }
    };
    const tbb::blocked_range<std::size_t> range(0, L.blocks().size(), 1);
    if (threaded)
        tbb::parallel_for(range, body);
    else
        body(range);
    Real m = INF;
    for (Real v : blockMin)
        m = std::min(m, v);
    return m;
}

template class Energy<2>;
template class Energy<3>;

} // namespace vdbmatch
