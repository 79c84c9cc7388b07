/// @file FieldSampler.cc
/// @brief Block storage of the shape fields and the quadratic B-spline quasi-interpolation
/// kernels (value, derivatives) used by the energy assembly.
/// @see paper [eq:defSi], [eq:EsymBend]

#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/FieldSampler.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>
#include <string>

namespace vdbmatch {

namespace {

using openvdb::Coord;

/// Queries whose node coordinate exceeds this magnitude are outside every tier (and would
/// overflow the int conversion).
constexpr double MAX_NODE_COORD = 1.0e9;

/// Quadratic B-spline constants: w_{-1} = HALF (HALF - t)^2, w_0 = THREE_QUARTERS - t^2,
/// w_{+1} = HALF (HALF + t)^2.
constexpr double HALF = 0.5;
constexpr double THREE_QUARTERS = 0.75;

using detail::forEachIndex;

inline void
splineWeights(double t, double* w)
{
    const double a = HALF - t, b = HALF + t;
    w[0] = HALF * a * a;
    w[1] = THREE_QUARTERS - t * t;
    w[2] = HALF * b * b;
}

inline void
splineDerivativeWeights(double t, double* dw)
{
    dw[0] = -(HALF - t);
    dw[1] = -2.0 * t;
    dw[2] = HALF + t;
}

/// Strides (in floats) of the apron block layout.
template <int D> struct Strides
{
    static constexpr int NC = FieldSampler<D>::NUM_COMPONENTS;
    static constexpr int X = NC;
    static constexpr int Y = FieldSampler<D>::APRON_DIM * NC;
    static constexpr int Z = FieldSampler<D>::APRON_DIM * FieldSampler<D>::APRON_DIM * NC;
};

/// Interpolates component 0 (d). w[a][k]: weight of tap k along axis a. This is the only code
/// that computes the interpolated d, for sampleDistance and sample alike.
template <int D>
inline double
interpolateDistance(const float* base, const double (*w)[3])
{
    using S = Strides<D>;
    auto row = [&](const float* r) {
        return w[0][0] * double(r[0]) + w[0][1] * double(r[S::X]) + w[0][2] * double(r[2 * S::X]);
    };
    auto plane = [&](const float* p) {
        return w[1][0] * row(p) + w[1][1] * row(p + S::Y) + w[1][2] * row(p + 2 * S::Y);
    };
    if constexpr (D == 2) {
        return plane(base);
    } else {
        return w[2][0] * plane(base) + w[2][1] * plane(base + S::Z) +
               w[2][2] * plane(base + 2 * S::Z);
    }
}

/// Interpolates all components; if WITH_DERIV also their derivatives in node units:
/// grad[a][c] = ∂(component c)/∂p_a.
template <int D, bool WITH_DERIV>
inline void
interpolateAll(const float* base, const double (*w)[3], const double (*dw)[3], double* value,
               double (*grad)[Strides<D>::NC])
{
    using S = Strides<D>;
    constexpr int NC = S::NC;
    constexpr int PLANES = D == 3 ? 3 : 1;
    // Per plane (z tap): value, ∂x, ∂y accumulated over the rows of the plane.
    double pv[PLANES][NC], px[PLANES][NC], py[PLANES][NC];
    for (int c = 0; c < PLANES; ++c) {
        for (int k = 0; k < NC; ++k)
            pv[c][k] = px[c][k] = py[c][k] = 0.0;
        for (int b = 0; b < 3; ++b) {
            const float* r = base + c * S::Z + b * S::Y;
            const double wy = w[1][b];
            for (int k = 0; k < NC; ++k) {
                const double f0 = r[k], f1 = r[S::X + k], f2 = r[2 * S::X + k];
                const double rv = w[0][0] * f0 + w[0][1] * f1 + w[0][2] * f2;
                pv[c][k] += wy * rv;
                if constexpr (WITH_DERIV) {
                    const double rd = dw[0][0] * f0 + dw[0][1] * f1 + dw[0][2] * f2;
                    px[c][k] += wy * rd;
                    py[c][k] += dw[1][b] * rv;
                }
            }
        }
    }
    if constexpr (D == 2) {
        for (int k = 0; k < NC; ++k) {
            value[k] = pv[0][k];
            if constexpr (WITH_DERIV) {
                grad[0][k] = px[0][k];
                grad[1][k] = py[0][k];
            }
        }
    } else {
        for (int k = 0; k < NC; ++k) {
            value[k] = w[2][0] * pv[0][k] + w[2][1] * pv[1][k] + w[2][2] * pv[2][k];
            if constexpr (WITH_DERIV) {
                grad[0][k] = w[2][0] * px[0][k] + w[2][1] * px[1][k] + w[2][2] * px[2][k];
                grad[1][k] = w[2][0] * py[0][k] + w[2][1] * py[1][k] + w[2][2] * py[2][k];
                grad[2][k] = dw[2][0] * pv[0][k] + dw[2][1] * pv[1][k] + dw[2][2] * pv[2][k];
            }
        }
    }
}

} // namespace

////////////////////////////////////////////////////////////////////////////////

template <int D>
FieldSampler<D>::FieldSampler(const std::vector<openvdb::FloatGrid::ConstPtr>& tiersFinestFirst,
                              const ShapeFieldOptions& opts)
{
    mTiers.reserve(tiersFinestFirst.size());
    for (size_t i = 0; i < tiersFinestFirst.size(); ++i) {
        if (!tiersFinestFirst[i]) {
            OPENVDB_THROW(openvdb::ValueError,
                          "FieldSampler: tier " + std::to_string(i) + " is a null grid");
        }
        const ShapeFields<D> fields(*tiersFinestFirst[i], opts);
        addTier(fields, opts.threaded);
    }
}

template <int D>
FieldSampler<D>::FieldSampler(const std::vector<const ShapeFields<D>*>& tiersFinestFirst,
                              bool threaded)
{
    mTiers.reserve(tiersFinestFirst.size());
    for (size_t i = 0; i < tiersFinestFirst.size(); ++i) {
        if (tiersFinestFirst[i] == nullptr) {
            OPENVDB_THROW(openvdb::ValueError,
                          "FieldSampler: tier " + std::to_string(i) + " has no fields");
        }
        addTier(*tiersFinestFirst[i], threaded);
    }
}

template <int D> FieldSampler<D>::FieldSampler(const std::vector<ConstPtr>& samplersFinestFirst)
{
    for (size_t i = 0; i < samplersFinestFirst.size(); ++i) {
        if (!samplersFinestFirst[i]) {
            OPENVDB_THROW(openvdb::ValueError,
                          "FieldSampler: sampler " + std::to_string(i) + " is null");
        }
        for (const auto& tier : samplersFinestFirst[i]->mTiers) {
            checkOrder(tier->h);
            mTiers.push_back(tier);
        }
    }
}

template <int D>
void
FieldSampler<D>::checkOrder(Real h) const
{
    if (!mTiers.empty() && h < mTiers.back()->h) {
        OPENVDB_THROW(openvdb::ValueError,
                      "FieldSampler: tiers must be ordered finest first, but tier " +
                          std::to_string(mTiers.size()) + " has voxel size " + std::to_string(h) +
                          " < " + std::to_string(mTiers.back()->h));
    }
}

template <int D>
void
FieldSampler<D>::addTier(const ShapeFields<D>& fields, bool threaded)
{
    constexpr int NC = NUM_COMPONENTS;
    constexpr int LOG2 = ShapeFields<D>::BLOCK_LOG2DIM;
    const Real h = fields.voxelSize();
    checkOrder(h);
    const size_t candidates = fields.blockCount();
    auto apronCoord = [&](int a) {
        return Coord(a % APRON_DIM, (a / APRON_DIM) % APRON_DIM,
                     D == 3 ? a / (APRON_DIM * APRON_DIM) : 0);
    };
    auto globalOfApron = [&](size_t b, int a) {
        const Coord shift(1, 1, D == 3 ? 1 : 0);
        return fields.blockOrigin(b) + apronCoord(a) - shift;
    };

    // 1. Stencil-complete flags of the owned nodes of every candidate block.
    std::vector<uint8_t> complete(candidates * BLOCK_NODES, 0);
    std::vector<size_t> completeCount(candidates, 0);
    forEachIndex(candidates, threaded, [&](size_t b) {
        std::array<uint8_t, APRON_NODES> valid;
        for (int a = 0; a < APRON_NODES; ++a) {
            const float* v = fields.nodeValues(globalOfApron(b, a));
            valid[a] = v != nullptr && !std::isnan(v[ShapeFields<D>::D_COMPONENT]);
        }
        size_t count = 0;
        for (int off = 0; off < BLOCK_NODES; ++off) {
            const int x = off % BLOCK_DIM, y = (off / BLOCK_DIM) % BLOCK_DIM;
            const int z = D == 3 ? off / (BLOCK_DIM * BLOCK_DIM) : 0;
            bool ok = true;
            for (int dz = 0; dz < (D == 3 ? 3 : 1) && ok; ++dz) {
                for (int dy = 0; dy < 3 && ok; ++dy) {
                    for (int dx = 0; dx < 3 && ok; ++dx) {
                        ok = valid[(x + dx) + APRON_DIM * ((y + dy) + APRON_DIM * (z + dz))];
                    }
                }
            }
            complete[b * BLOCK_NODES + size_t(off)] = ok ? 1 : 0;
            count += ok ? 1 : 0;
        }
        completeCount[b] = count;
    });

    // 2. Keep the blocks with at least one complete stencil (order preserved).
    std::vector<size_t> kept;
    std::vector<Coord> blockCoords;
    for (size_t b = 0; b < candidates; ++b) {
        if (completeCount[b] == 0) continue;
        kept.push_back(b);
        const Coord& o = fields.blockOrigin(b);
        blockCoords.push_back(Coord(o[0] >> LOG2, o[1] >> LOG2, o[2] >> LOG2));
    }

    Tier tier;
    tier.h = h;
    tier.invH = 1.0 / h;
    tier.blocks = kept.size();
    tier.table.build(blockCoords);
    tier.complete.resize(kept.size() * BLOCK_NODES);
    tier.values.resize(kept.size() * size_t(APRON_NODES * NC));

    // 3. Copy the fields including the apron.
    constexpr float NOT_A_FIELD = std::numeric_limits<float>::quiet_NaN();
    forEachIndex(kept.size(), threaded, [&](size_t k) {
        const size_t b = kept[k];
        std::copy_n(&complete[b * BLOCK_NODES], BLOCK_NODES, &tier.complete[k * BLOCK_NODES]);
        float* out = tier.values.data() + k * size_t(APRON_NODES * NC);
        for (int a = 0; a < APRON_NODES; ++a) {
            const float* v = fields.nodeValues(globalOfApron(b, a));
            for (int c = 0; c < NC; ++c)
                out[a * NC + c] = v ? v[c] : NOT_A_FIELD;
        }
    });
    mTiers.push_back(std::make_shared<const Tier>(std::move(tier)));
}

template <int D>
size_t
FieldSampler<D>::memoryUsage() const
{
    size_t bytes = sizeof(*this);
    for (const auto& tier : mTiers) {
        const Tier& t = *tier;
        bytes += sizeof(Tier) + t.table.memoryUsage() + t.values.size() * sizeof(float) +
                 t.complete.size() * sizeof(uint8_t);
    }
    return bytes;
}

template <int D>
const float*
FieldSampler<D>::locate(const Vec<D>& x, Real* t, int& tierIndex) const
{
    constexpr int LOG2 = ShapeFields<D>::BLOCK_LOG2DIM;
    constexpr int MASK = BLOCK_DIM - 1;
    for (size_t ti = 0; ti < mTiers.size(); ++ti) {
        const Tier& tier = *mTiers[ti];
        int r[3] = {0, 0, 0};
        bool inRange = true;
        for (int a = 0; a < D; ++a) {
            const double p = x[a] * tier.invH;
            // Quiet comparison: NaN positions must not raise FE_INVALID (trapped in Debug tests).
            if (!std::isless(std::abs(p), MAX_NODE_COORD)) {
                inRange = false;
                break;
            }
            const double rounded = std::floor(p + HALF);
            r[a] = int(rounded);
            t[a] = p - rounded;
        }
        if (!inRange) continue;
        const int32_t b = tier.table.find(r[0] >> LOG2, r[1] >> LOG2, r[2] >> LOG2);
        if (b < 0) continue;
        const int lx = r[0] & MASK, ly = r[1] & MASK, lz = D == 3 ? r[2] & MASK : 0;
        const int owned = lx + BLOCK_DIM * (ly + BLOCK_DIM * lz);
        if (!tier.complete[size_t(b) * BLOCK_NODES + size_t(owned)]) continue;
        // The owned node l sits at apron position l + 1, so the stencil corner is at l.
        const int corner = lx + APRON_DIM * (ly + APRON_DIM * lz);
        tierIndex = int(ti);
        return tier.values.data() + (size_t(b) * APRON_NODES + size_t(corner)) * NUM_COMPONENTS;
    }
    return nullptr;
}

template <int D>
int
FieldSampler<D>::findTier(const Vec<D>& x) const
{
    Real t[D];
    int tier = -1;
    return locate(x, t, tier) ? tier : -1;
}

template <int D>
bool
FieldSampler<D>::sampleDistance(const Vec<D>& x, Real& d) const
{
    return sampleDistance(x, d, nullptr);
}

// flatten (here and in sample()): locate() and the interpolation inlined, the same bits.
template <int D>
__attribute__((flatten)) bool
FieldSampler<D>::sampleDistance(const Vec<D>& x, Real& d, int& tierIndex) const
{
    Real t[D];
    const float* base = locate(x, t, tierIndex);
    if (base == nullptr) return false;
    double w[D][3];
    for (int a = 0; a < D; ++a)
        splineWeights(t[a], w[a]);
    d = interpolateDistance<D>(base, w);
    return true;
}

template <int D>
__attribute__((flatten)) bool
FieldSampler<D>::sampleDistance(const Vec<D>& x, Real& d, Real* tierVoxelSize) const
{
    int tier = -1;
    if (!sampleDistance(x, d, tier)) return false;
    if (tierVoxelSize) *tierVoxelSize = mTiers[size_t(tier)]->h;
    return true;
}

template <int D>
bool
FieldSampler<D>::sameStencil(const Vec<D>& x, const Vec<D>& x0, int tierIndex) const
{
    if (tierIndex < 0 || size_t(tierIndex) >= mTiers.size()) return false;
    // locate() picks the first tier whose stencil around round(x / h) is complete: the same
    // rounding in every tier up to this one gives the same choice and the same stencil.
    // (Compared as doubles: a NaN position compares unequal.)
    for (int ti = 0; ti <= tierIndex; ++ti) {
        const Real invH = mTiers[size_t(ti)]->invH;
        for (int a = 0; a < D; ++a)
            if (!(std::floor(x[a] * invH + HALF) == std::floor(x0[a] * invH + HALF))) return false;
    }
    return true;
}

template <int D>
__attribute__((flatten)) bool
FieldSampler<D>::sample(const Vec<D>& x, RawFields<D>& fields, RawFieldDerivatives<D>* deriv) const
{
    constexpr int NC = NUM_COMPONENTS;
    constexpr int N0 = ShapeFields<D>::N_COMPONENT;
    constexpr int R0 = ShapeFields<D>::R_COMPONENT;
    Real t[D];
    int tierIndex = -1;
    const float* base = locate(x, t, tierIndex);
    if (base == nullptr) return false;
    double w[D][3];
    for (int a = 0; a < D; ++a)
        splineWeights(t[a], w[a]);
    double value[NC];
    if (deriv == nullptr) {
        interpolateAll<D, false>(base, w, nullptr, value, nullptr);
    } else {
        double dw[D][3];
        for (int a = 0; a < D; ++a)
            splineDerivativeWeights(t[a], dw[a]);
        double grad[D][NC];
        interpolateAll<D, true>(base, w, dw, value, grad);
        const double invH = mTiers[size_t(tierIndex)]->invH;
        for (int k = 0; k < D; ++k) {
            deriv->dd[k] = grad[k][0] * invH;
            for (int i = 0; i < D; ++i)
                deriv->dn(i, k) = grad[k][N0 + i] * invH;
            for (int i = 0; i < D; ++i) {
                for (int j = i; j < D; ++j) {
                    deriv->dR[k](i, j) = deriv->dR[k](j, i) =
                        grad[k][R0 + ShapeFields<D>::symIndex(i, j)] * invH;
                }
            }
        }
    }
    fields.d = interpolateDistance<D>(base, w);
    for (int i = 0; i < D; ++i)
        fields.n[i] = value[N0 + i];
    for (int i = 0; i < D; ++i) {
        for (int j = i; j < D; ++j) {
            fields.R(i, j) = fields.R(j, i) = value[R0 + ShapeFields<D>::symIndex(i, j)];
        }
    }
    return true;
}

template class FieldSampler<2>;
template class FieldSampler<3>;

} // namespace vdbmatch
