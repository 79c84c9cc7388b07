#include <vdbmatch/geometry/DenseLattice.h>
#include <vdbmatch/geometry/InnerDistance.h>

#include <openvdb/openvdb.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <utility>

namespace vdbmatch {

namespace {

enum : uint8_t { FAR = 0, TRIAL = 1, DONE = 2 };

using detail::DenseIndex;

/// The first-order fast marching method on the nodes that @a allowed admits.
template <int D> class FastMarch
{
public:
    FastMarch(const DenseIndex<D>& index, Real h, std::vector<Real>& values,
              std::vector<uint8_t>& state)
        : mIndex(index), mH(h), mValues(values), mState(state)
    {
    }

    /// Offers @a value to node @a i (a seed, or an update).
    void offer(int64_t i, Real value)
    {
        if (mState[std::size_t(i)] == DONE || !(value < mValues[std::size_t(i)])) return;
        mValues[std::size_t(i)] = value;
        mState[std::size_t(i)] = TRIAL;
        mQueue.emplace(value, i);
    }

    /// The upwind solution at node @a i from its accepted axis neighbours: the largest t with
    /// sum_a max(t - m_a, 0)^2 = h^2, m_a the smaller accepted neighbour along axis a
    /// (infinity when there is none).
    Real update(int64_t i) const
    {
        const std::array<int, D> c = mIndex.coords(i);
        std::array<Real, D> m;
        int k = 0;
        for (int a = 0; a < D; ++a) {
            Real best = INF;
            const int64_t s = mIndex.stride[a];
            if (c[a] > 0 && mState[std::size_t(i - s)] == DONE) best = mValues[std::size_t(i - s)];
            if (c[a] < mIndex.n && mState[std::size_t(i + s)] == DONE)
                best = std::min(best, mValues[std::size_t(i + s)]);
            if (best < INF) m[k++] = best;
        }
        if (k == 0) return INF;
        for (int q = 1; q < k; ++q) // insertion sort of at most three values
            for (int r = q; r > 0 && m[r] < m[r - 1]; --r)
                std::swap(m[r], m[r - 1]);
        Real t = m[0] + mH;
        for (int q = 1; q < k && t > m[q]; ++q) {
            Real s = 0, s2 = 0;
            for (int r = 0; r <= q; ++r) {
                s += m[r];
                s2 += m[r] * m[r];
            }
            const Real disc = s * s - Real(q + 1) * (s2 - mH * mH);
            t = (s + std::sqrt(std::max(disc, Real(0)))) / Real(q + 1);
        }
        return t;
    }

    /// Accepts nodes in increasing value (ties: the lower index) until the queue is empty,
    /// calling @a accepted on each and updating its admitted neighbours.
    template <typename Allowed, typename Accepted> void run(Allowed&& allowed, Accepted&& accepted)
    {
        while (!mQueue.empty()) {
            const auto [d, i] = mQueue.top();
            mQueue.pop();
            if (mState[std::size_t(i)] == DONE || d > mValues[std::size_t(i)]) continue;
            mState[std::size_t(i)] = DONE;
            accepted(i);
            const std::array<int, D> c = mIndex.coords(i);
            for (int a = 0; a < D; ++a) {
                for (int sign = -1; sign <= 1; sign += 2) {
                    const int x = c[a] + sign;
                    if (x < 0 || x > mIndex.n) continue;
                    const int64_t j = i + sign * mIndex.stride[a];
                    if (mState[std::size_t(j)] == DONE || !allowed(j)) continue;
                    offer(j, update(j));
                }
            }
        }
    }

private:
    using Entry = std::pair<Real, int64_t>;
    const DenseIndex<D>& mIndex;
    Real mH;
    std::vector<Real>& mValues;
    std::vector<uint8_t>& mState;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> mQueue;
};

} // namespace

template <int D>
bool
InnerDistanceField<D>::sample(const Vec<D>& x, Real& f, Vec<D>* gradient) const
{
    if (empty()) return false;
    std::array<int, D> cell;
    std::array<Real, D> t;
    std::array<bool, D> clamped;
    int64_t base = 0, stride = 1;
    std::array<int64_t, D> strides;
    for (int a = 0; a < D; ++a) {
        clamped[a] = !(x[a] >= 0 && x[a] <= 1);
        const Real xa = std::clamp(x[a], Real(0), Real(1)) / h;
        cell[a] = std::min(int(std::floor(xa)), n - 1);
        t[a] = xa - Real(cell[a]);
        strides[a] = stride;
        base += cell[a] * stride;
        stride *= n + 1;
    }
    f = 0;
    if (gradient) gradient->setZero();
    for (int corner = 0; corner < (1 << D); ++corner) {
        int64_t i = base;
        Real w = 1;
        std::array<Real, D> factor;
        for (int a = 0; a < D; ++a) {
            const bool up = corner & (1 << a);
            factor[a] = up ? t[a] : 1 - t[a];
            w *= factor[a];
            if (up) i += strides[a];
        }
        const Real v = Real(values[std::size_t(i)]);
        f += w * v;
        if (gradient) {
            for (int a = 0; a < D; ++a) {
                if (clamped[a]) continue;
                Real g = (corner & (1 << a)) ? 1 / h : -1 / h;
                for (int b = 0; b < D; ++b)
                    if (b != a) g *= factor[b];
                (*gradient)[a] += g * v;
            }
        }
    }
    return true;
}

namespace {

/// F from one source, on the inside mask of the dense lattice.
template <int D>
InnerDistanceField<D>
marchFrom(const Vec<D>& p, const std::vector<uint8_t>& inside, const DenseIndex<D>& index,
          int level, std::size_t insideNodes)
{
    InnerDistanceField<D> out;
    out.level = level;
    out.n = index.n;
    out.h = std::ldexp(Real(1), -level);
    out.insideNodes = insideNodes;
    std::vector<Real> values(std::size_t(index.size), INF);
    std::vector<uint8_t> state(std::size_t(index.size), FAR);
    FastMarch<D> march(index, out.h, values, state);
    const auto position = [&](int64_t i) {
        const std::array<int, D> c = index.coords(i);
        Vec<D> x;
        for (int a = 0; a < D; ++a)
            x[a] = out.h * Real(c[a]);
        return x;
    };
    // Seeds: the inside corners of the source's cell, else the nearest inside node.
    int64_t base = 0;
    for (int a = 0; a < D; ++a) {
        const Real xa = std::clamp(p[a], Real(0), Real(1)) / out.h;
        base += std::min(int(std::floor(xa)), out.n - 1) * index.stride[a];
    }
    for (int corner = 0; corner < (1 << D); ++corner) {
        int64_t i = base;
        for (int a = 0; a < D; ++a)
            if (corner & (1 << a)) i += index.stride[a];
        if (!inside[std::size_t(i)]) continue;
        march.offer(i, (position(i) - p).norm());
        ++out.sourceNodes;
    }
    if (out.sourceNodes == 0) {
        int64_t nearest = -1;
        Real best = INF;
        for (int64_t i = 0; i < index.size; ++i) {
            if (!inside[std::size_t(i)]) continue;
            const Real r = (position(i) - p).squaredNorm();
            if (r < best) {
                best = r;
                nearest = i;
            }
        }
        if (nearest < 0) {
            out.values.assign(std::size_t(index.size), std::numeric_limits<float>::infinity());
            return out;
        }
        march.offer(nearest, std::sqrt(best));
        out.sourceNodes = 1;
    }
    // 1. Inside, from the source.
    march.run([&](int64_t j) { return inside[std::size_t(j)] != 0; }, [](int64_t) {});
    for (int64_t i = 0; i < index.size; ++i)
        out.reachedInside += inside[std::size_t(i)] && state[std::size_t(i)] == DONE;
    // 2. Everywhere else, in increasing distance u from the accepted nodes (a march of u of its
    //    own): each node takes the upwind value of F from its neighbours already set, so that
    //    F next to the surface comes from its own side, never across a gap of the outside
    //    (between a hanging arm and the body, the slot of a U), where a march of F itself would
    //    bring the far side's smaller values.
    std::vector<Real> u(std::size_t(index.size), INF);
    std::vector<uint8_t> uState(std::size_t(index.size), FAR);
    FastMarch<D> outside(index, out.h, u, uState);
    for (int64_t i = 0; i < index.size; ++i) {
        if (state[std::size_t(i)] != DONE) continue;
        u[std::size_t(i)] = 0;
        uState[std::size_t(i)] = DONE;
    }
    for (int64_t i = 0; i < index.size; ++i) {
        if (uState[std::size_t(i)] == DONE) continue;
        const Real t = outside.update(i);
        if (t < INF) outside.offer(i, t);
    }
    outside.run([](int64_t) { return true; },
                [&](int64_t i) {
                    values[std::size_t(i)] = march.update(i);
                    state[std::size_t(i)] = DONE;
                });
    out.values.assign(values.begin(), values.end());
    return out;
}

} // namespace

template <int D>
std::vector<InnerDistanceField<D>>
innerDistanceFields(const Surface<D>& unitSurface, const std::vector<Vec<D>>& sources, int level,
                    bool threaded)
{
    for (const Vec<D>& p : sources) {
        if (!p.allFinite())
            OPENVDB_THROW(openvdb::ValueError,
                          "innerDistanceFields: a source point has a coordinate that is not "
                          "finite");
    }
    float background = 0;
    const std::vector<float> distance =
        detail::denseBandDistance<D>(unitSurface, level, threaded, background);
    const DenseIndex<D> index(1 << level);
    std::vector<uint8_t> inside(std::size_t(index.size), 0);
    std::size_t insideNodes = 0;
    for (int64_t i = 0; i < index.size; ++i) {
        inside[std::size_t(i)] = distance[std::size_t(i)] < 0;
        insideNodes += inside[std::size_t(i)];
    }
    std::vector<InnerDistanceField<D>> out(sources.size());
    const auto body = [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k != r.end(); ++k)
            out[k] = marchFrom<D>(sources[k], inside, index, level, insideNodes);
    };
    const tbb::blocked_range<std::size_t> range(0, sources.size(), 1);
    if (threaded)
        tbb::parallel_for(range, body);
    else
        body(range);
    return out;
}

template <int D>
int
ownSource(const std::vector<InnerDistanceField<D>>& fields, const Vec<D>& x, double ratio,
          Real& value)
{
    if (!(ratio >= 1) || !std::isfinite(ratio))
        OPENVDB_THROW(openvdb::ValueError,
                      "ownSource: the ratio must be finite and >= 1, got " << ratio);
    Real best = INF, next = INF;
    int own = -1;
    for (std::size_t k = 0; k < fields.size(); ++k) {
        Real f;
        if (!fields[k].sample(x, f)) continue;
        if (f < best) { // the first of equals
            next = best;
            best = f;
            own = int(k);
        } else if (f < next) {
            next = f;
        }
    }
    value = best;
    if (own < 0 || next < Real(ratio) * best) return -1;
    return own;
}

template struct InnerDistanceField<2>;
template struct InnerDistanceField<3>;
template std::vector<InnerDistanceField<2>>
innerDistanceFields<2>(const Surface<2>&, const std::vector<Vec<2>>&, int, bool);
template std::vector<InnerDistanceField<3>>
innerDistanceFields<3>(const Surface<3>&, const std::vector<Vec<3>>&, int, bool);

template int ownSource<2>(const std::vector<InnerDistanceField<2>>&, const Vec<2>&, double, Real&);
template int ownSource<3>(const std::vector<InnerDistanceField<3>>&, const Vec<3>&, double, Real&);

} // namespace vdbmatch
