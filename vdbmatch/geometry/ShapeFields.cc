/// @file ShapeFields.cc
/// @brief Finite-difference computation of d, n = ∇d/|∇d| and R = S^{1/2} at the nodes of a
/// signed-distance grid, with optional binomial smoothing of the Hessian field.
/// @see paper [subsec:notation], [eq:defSi]

#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/ShapeFields.h>

#include <openvdb/tools/Diagnostics.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>
#include <string>

namespace vdbmatch {

namespace {

using openvdb::Coord;

/// tools::checkLevelSet runs its checks 1..8 (value type, class, uniform scale, background,
/// no active tiles, finite values, range, inactive values = ±background); check 9 (Eikonal)
/// would reject exact distances with kinks, e.g. at the centre of a sphere.
constexpr size_t LEVEL_SET_CHECKS = 8;

/// Relative tolerance on the transform: index-to-world must be ijk -> ijk*h.
constexpr double TRANSFORM_TOLERANCE = 1e-9;

/// Weights of the binomial smoothing stencil [1,2,1]/4.
constexpr double BINOMIAL_SIDE = 0.25;
constexpr double BINOMIAL_CENTER = 0.5;

using detail::forEachIndex;

/// Node layout inside a block of 8^D nodes: x fastest.
template <int D> struct BlockLayout
{
    static constexpr int DIM = ShapeFields<D>::BLOCK_DIM;
    static constexpr int NODES = ShapeFields<D>::BLOCK_NODES;
    static constexpr int MASK = DIM - 1;

    static int offset(const Coord& local)
    {
        return local[0] + DIM * (local[1] + (D == 3 ? DIM * local[2] : 0));
    }
    static Coord local(int offset)
    {
        return Coord(offset & MASK, (offset >> 3) & MASK, D == 3 ? offset >> 6 : 0);
    }
};

/// Unit vector along axis a.
inline Coord
axisCoord(int a, int s = 1)
{
    Coord e(0, 0, 0);
    e[a] = s;
    return e;
}

/// Finite differences at one node. Returns false if any stencil voxel is inactive or the gradient
/// vanishes.
template <int D, typename AccessorT>
bool
computeRawNode(AccessorT& acc, const Coord& ijk, double h, double& d, Vec<D>& n, Mat<D>& H)
{
    /// |grad d| below this (an SDF has |grad d| = 1) marks a medial-axis node.
    constexpr double DEGENERATE_GRADIENT = 1e-3;
    float value = 0.0f;
    if (!acc.probeValue(ijk, value)) return false;
    const double v0 = value;
    const double invH2 = 1.0 / (h * h);
    Vec<D> g;
    for (int a = 0; a < D; ++a) {
        float vp = 0.0f, vm = 0.0f;
        if (!acc.probeValue(ijk + axisCoord(a), vp)) return false;
        if (!acc.probeValue(ijk + axisCoord(a, -1), vm)) return false;
        g[a] = (double(vp) - double(vm)) / (2.0 * h);
        H(a, a) = (double(vp) - 2.0 * v0 + double(vm)) * invH2;
    }
    for (int a = 0; a < D; ++a) {
        for (int b = a + 1; b < D; ++b) {
            float vpp = 0.0f, vpm = 0.0f, vmp = 0.0f, vmm = 0.0f;
            const Coord ea = axisCoord(a), eb = axisCoord(b);
            if (!acc.probeValue(ijk + ea + eb, vpp)) return false;
            if (!acc.probeValue(ijk + ea - eb, vpm)) return false;
            if (!acc.probeValue(ijk - ea + eb, vmp)) return false;
            if (!acc.probeValue(ijk - ea - eb, vmm)) return false;
            H(a, b) = H(b, a) =
                ((double(vpp) - double(vpm)) - (double(vmp) - double(vmm))) * (0.25 * invH2);
        }
    }
    const double gNorm = g.norm();
    if (!std::isfinite(gNorm) || !H.allFinite()) return false;
    d = v0;
    // On the medial axis (e.g. the centre of a sphere) the central difference gradient can
    // vanish; any unit vector is then as good as another. The band terms never sample there as
    // long as sigma is below the reach of the shape, but the distance must stay available.
    n = gNorm > DEGENERATE_GRADIENT ? Vec<D>(g / gNorm) : Vec<D>(Vec<D>::UnitX());
    return true;
}

} // namespace

////////////////////////////////////////////////////////////////////////////////

void
detail::DenseBlockTable::build(const std::vector<Coord>& blockCoords)
{
    mIndex.clear();
    mMin = Coord(0, 0, 0);
    mDim = {{0, 0, 0}};
    if (blockCoords.empty()) return;
    Coord lo = blockCoords.front(), hi = blockCoords.front();
    for (const Coord& c : blockCoords) {
        lo.minComponent(c);
        hi.maxComponent(c);
    }
    mMin = lo;
    for (int a = 0; a < 3; ++a)
        mDim[a] = uint32_t(hi[a] - lo[a] + 1);
    mIndex.assign(size_t(mDim[0]) * mDim[1] * mDim[2], -1);
    for (size_t i = 0; i < blockCoords.size(); ++i) {
        const Coord r = blockCoords[i] - mMin;
        mIndex[(size_t(r[2]) * mDim[1] + size_t(r[1])) * mDim[0] + size_t(r[0])] = int32_t(i);
    }
}

int
lengthSmoothingPasses(double s, double h)
{
    if (!(s > 0.0 && h > 0.0)) return 0;
    return int(std::min(std::round(2.0 * (s / h) * (s / h)), double(MAX_LENGTH_SMOOTHING_PASSES)));
}

int
pairSmoothingPasses(double sourceLength, double targetLength, double h)
{
    return std::max(lengthSmoothingPasses(sourceLength, h), lengthSmoothingPasses(targetLength, h));
}

int
hessianSmoothingPasses(const ShapeFieldOptions& opts, double h)
{
    return std::max(opts.hessianSmoothing, 0) +
           lengthSmoothingPasses(opts.hessianSmoothingLength, h);
}

Real
validateDistanceGrid(const openvdb::FloatGrid& grid, const char* caller)
{
    const std::string prefix = std::string(caller) + ": grid \"" + grid.getName() + "\" ";
    const std::string problem = openvdb::tools::checkLevelSet(grid, LEVEL_SET_CHECKS);
    if (!problem.empty()) {
        OPENVDB_THROW(openvdb::ValueError,
                      prefix + "is not a valid signed-distance level set: " + problem);
    }
    const openvdb::math::Transform& xform = grid.transform();
    const double h = grid.voxelSize()[0];
    bool isScale = xform.isLinear() && h > 0.0;
    const openvdb::Vec3d origin = xform.indexToWorld(openvdb::Vec3d(0.0));
    isScale = isScale && origin.length() <= TRANSFORM_TOLERANCE * h;
    for (int a = 0; a < 3 && isScale; ++a) {
        openvdb::Vec3d e(0.0), expected(0.0);
        e[a] = 1.0;
        expected[a] = h;
        isScale = (xform.indexToWorld(e) - expected).length() <= TRANSFORM_TOLERANCE * h;
    }
    if (!isScale) {
        OPENVDB_THROW(openvdb::ValueError,
                      prefix + "must have the transform ijk -> ijk*h (uniform scale, no "
                               "translation or rotation)");
    }
    return h;
}

template <int D>
ShapeFields<D>::ShapeFields(const openvdb::FloatGrid& grid, const ShapeFieldOptions& opts)
    : mOptions(opts)
{
    if (!(opts.tau > 0.0) || !std::isfinite(opts.tau)) {
        OPENVDB_THROW(openvdb::ValueError, "ShapeFields: tau must be positive and finite, got " +
                                               std::to_string(opts.tau));
    }
    if (opts.hessianSmoothing < 0) {
        OPENVDB_THROW(openvdb::ValueError, "ShapeFields: hessianSmoothing must be >= 0, got " +
                                               std::to_string(opts.hessianSmoothing));
    }
    if (!(opts.hessianSmoothingLength >= 0.0) || !std::isfinite(opts.hessianSmoothingLength)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "ShapeFields: hessianSmoothingLength must be >= 0 and finite, got " +
                          std::to_string(opts.hessianSmoothingLength));
    }
    mVoxelSize = validateDistanceGrid(grid, "ShapeFields");
    const double h = mVoxelSize;
    using Layout = BlockLayout<D>;
    constexpr int NODES = Layout::NODES;
    constexpr int NC = NUM_COMPONENTS;
    constexpr int SYM = SYM_COMPONENTS;
    constexpr size_t BLOCK_FLOATS = size_t(NC) * NODES;
    constexpr float NOT_A_FIELD = std::numeric_limits<float>::quiet_NaN();

    // Candidate blocks: the leaf nodes (in 2D those holding the slice k = 0), in tree order.
    std::vector<Coord> origins;
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        const Coord origin = leaf->origin();
        if (D == 2 && origin[2] != 0) continue;
        origins.push_back(origin);
    }

    // 1. Finite differences, stored in place: d, n and the Hessian in the slots of R.
    mValues.assign(origins.size() * BLOCK_FLOATS, NOT_A_FIELD);
    std::vector<size_t> validPerBlock(origins.size(), 0);
    forEachIndex(origins.size(), opts.threaded, [&](size_t b) {
        auto acc = grid.getConstAccessor();
        size_t count = 0;
        for (int off = 0; off < NODES; ++off) {
            double d = 0.0;
            Vec<D> n;
            Mat<D> H;
            if (!computeRawNode<D>(acc, origins[b] + Layout::local(off), h, d, n, H)) continue;
            float* out = mValues.data() + b * BLOCK_FLOATS + size_t(off) * NC;
            out[D_COMPONENT] = float(d);
            for (int a = 0; a < D; ++a)
                out[N_COMPONENT + a] = float(n[a]);
            for (int i = 0; i < D; ++i)
                for (int j = i; j < D; ++j)
                    out[R_COMPONENT + symIndex(i, j)] = float(H(i, j));
            ++count;
        }
        validPerBlock[b] = count;
    });

    // 2. Keep the blocks that have at least one valid node (order preserved, compacted in place).
    std::vector<Coord> blockCoords;
    for (size_t b = 0; b < origins.size(); ++b) {
        if (validPerBlock[b] == 0) continue;
        const size_t k = mOrigins.size();
        if (k != b) {
            std::copy_n(mValues.begin() + std::ptrdiff_t(b * BLOCK_FLOATS), BLOCK_FLOATS,
                        mValues.begin() + std::ptrdiff_t(k * BLOCK_FLOATS));
        }
        mOrigins.push_back(origins[b]);
        blockCoords.push_back(Coord(origins[b][0] >> BLOCK_LOG2DIM, origins[b][1] >> BLOCK_LOG2DIM,
                                    origins[b][2] >> BLOCK_LOG2DIM));
        mValidNodeCount += validPerBlock[b];
    }
    mValues.resize(mOrigins.size() * BLOCK_FLOATS);
    mValues.shrink_to_fit();
    mTable.build(blockCoords);

    // 3. Hessian smoothing: separable binomial passes, one axis at a time.
    const int passes = hessianSmoothingPasses(opts, h);
    if (passes > 0) {
        std::vector<float> smoothed(mOrigins.size() * size_t(NODES) * SYM);
        for (int iter = 0; iter < passes; ++iter) {
            for (int axis = 0; axis < D; ++axis) {
                forEachIndex(mOrigins.size(), opts.threaded, [&](size_t k) {
                    for (int off = 0; off < NODES; ++off) {
                        const float* node = blockValues(k) + size_t(off) * NC;
                        float* out = &smoothed[(k * NODES + size_t(off)) * SYM];
                        const float* minus = nullptr;
                        const float* plus = nullptr;
                        if (!std::isnan(node[D_COMPONENT])) {
                            const Coord ijk = mOrigins[k] + Layout::local(off);
                            minus = nodeValues(ijk - axisCoord(axis));
                            plus = nodeValues(ijk + axisCoord(axis));
                        }
                        const bool smooth = minus && plus && !std::isnan(minus[D_COMPONENT]) &&
                                            !std::isnan(plus[D_COMPONENT]);
                        for (int c = 0; c < SYM; ++c) {
                            const int slot = R_COMPONENT + c;
                            out[c] = smooth ? float(BINOMIAL_SIDE *
                                                        (double(minus[slot]) + double(plus[slot])) +
                                                    BINOMIAL_CENTER * double(node[slot]))
                                            : node[slot];
                        }
                    }
                });
                forEachIndex(mOrigins.size(), opts.threaded, [&](size_t k) {
                    float* block = mValues.data() + k * BLOCK_FLOATS;
                    for (int off = 0; off < NODES; ++off) {
                        std::copy_n(&smoothed[(k * NODES + size_t(off)) * SYM], SYM,
                                    block + size_t(off) * NC + R_COMPONENT);
                    }
                });
            }
        }
    }

    // 4. Replace the Hessian by the regularized square root R of the shape operator.
    forEachIndex(mOrigins.size(), opts.threaded, [&](size_t k) {
        float* block = mValues.data() + k * BLOCK_FLOATS;
        for (int off = 0; off < NODES; ++off) {
            float* v = block + size_t(off) * NC;
            if (std::isnan(v[D_COMPONENT])) continue;
            Vec<D> n;
            Mat<D> H;
            for (int a = 0; a < D; ++a)
                n[a] = v[N_COMPONENT + a];
            n.normalize();
            for (int i = 0; i < D; ++i)
                for (int j = 0; j < D; ++j)
                    H(i, j) = v[R_COMPONENT + symIndex(i, j)];
            const Mat<D> R = regularizedShapeOperatorSqrt<D>(H, n, opts.tau);
            for (int i = 0; i < D; ++i)
                for (int j = i; j < D; ++j)
                    v[R_COMPONENT + symIndex(i, j)] = float(R(i, j));
        }
    });
}

template <int D>
const float*
ShapeFields<D>::nodeValues(const openvdb::Coord& ijk) const
{
    const Coord c(ijk[0], ijk[1], D == 3 ? ijk[2] : 0);
    const int32_t b =
        mTable.find(c[0] >> BLOCK_LOG2DIM, c[1] >> BLOCK_LOG2DIM, c[2] >> BLOCK_LOG2DIM);
    if (b < 0) return nullptr;
    constexpr int MASK = BLOCK_DIM - 1;
    const Coord local(c[0] & MASK, c[1] & MASK, c[2] & MASK);
    return blockValues(size_t(b)) + size_t(BlockLayout<D>::offset(local)) * NUM_COMPONENTS;
}

template <int D>
bool
ShapeFields<D>::getNode(const openvdb::Coord& ijk, NodeFields<D>& fields) const
{
    const float* v = nodeValues(ijk);
    if (v == nullptr || std::isnan(v[D_COMPONENT])) return false;
    fields.d = v[D_COMPONENT];
    for (int a = 0; a < D; ++a)
        fields.n[a] = v[N_COMPONENT + a];
    for (int i = 0; i < D; ++i)
        for (int j = 0; j < D; ++j)
            fields.R(i, j) = v[R_COMPONENT + symIndex(i, j)];
    return true;
}

template class ShapeFields<2>;
template class ShapeFields<3>;

} // namespace vdbmatch
