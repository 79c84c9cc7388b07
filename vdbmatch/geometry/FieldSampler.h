/// @file FieldSampler.h
/// @brief C¹ quadratic B-spline quasi-interpolation of the shape fields d, n and R = S^{1/2}, with
/// fallback from fine to coarse tiers.
///
/// Every field f with node values f_i (ShapeFields) is evaluated with Schoenberg's quadratic
/// quasi-interpolant
/// @f[ (Qf)(x) = \sum_{i} f_i \prod_{a=1}^{D} B_2(x_a/h - i_a), @f]
/// B_2 the centred quadratic B-spline. With p = x/h (node units), r = round(p) and t = p - r,
/// the three taps r-1, r, r+1 of an axis have the weights
/// @f[ w_{-1} = \tfrac12(\tfrac12 - t)^2,\quad w_0 = \tfrac34 - t^2,\quad
///     w_{+1} = \tfrac12(\tfrac12 + t)^2 @f]
/// and the derivatives -(1/2 - t), -2t, 1/2 + t (times 1/h); 3^D taps in total. Qf is C¹ with
/// knots at the half-integers, reproduces linear functions exactly and is O(h²) accurate, and
/// its derivatives are O(h²) accurate too. It is not interpolating: Qf = f + (h²/8) Δf + O(h⁴)
/// (exactly so for quadratics), e.g. d is shifted by (h²/8) times the sum of the curvatures.
/// Values and derivatives come from the same interpolant, so an energy assembled from them has
/// an exact gradient.
///
/// Spaces: positions x are in Omega coordinates (node i of a tier is at x = i*h of that tier,
/// i.e. the world space of the input grids); derivatives are with respect to x.
///
/// @see paper [subsec:notation], [eq:defSi], [eq:EsymBend]
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/RawFields.h>
#include <vdbmatch/geometry/ShapeFields.h>

#include <openvdb/openvdb.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace vdbmatch {

/// Quadratic B-spline quasi-interpolant of the per-node fields d, n, R of a shape, over tiers
/// ordered finest first. A query uses the finest tier whose 3^D stencil consists of nodes with
/// fields; if there is none it returns false.
///
/// Storage per tier: blocks of 8^D owned nodes plus a one-node apron on every side (10^D nodes,
/// ShapeFields<D>::NUM_COMPONENTS floats per node, x fastest), so that every stencil lies in one
/// block, found through a dense table of block indices over the tier's bounding box, and one
/// "stencil complete" flag per owned node.
///
/// Thread-safety: the query functions are const and may be called concurrently.
template <int D> class FieldSampler
{
public:
    static_assert(D == 2 || D == 3, "FieldSampler: D must be 2 or 3");

    using Ptr = std::shared_ptr<FieldSampler>;
    using ConstPtr = std::shared_ptr<const FieldSampler>;

    static constexpr int NUM_COMPONENTS = ShapeFields<D>::NUM_COMPONENTS;
    static constexpr int BLOCK_DIM = ShapeFields<D>::BLOCK_DIM;
    static constexpr int BLOCK_NODES = ShapeFields<D>::BLOCK_NODES;
    static constexpr int APRON_DIM = BLOCK_DIM + 2;
    static constexpr int APRON_NODES =
        D == 2 ? APRON_DIM * APRON_DIM : APRON_DIM * APRON_DIM * APRON_DIM;

    /// An empty sampler: every query returns false.
    FieldSampler() = default;

    /// Computes the fields of each grid (ShapeFields) and stores them.
    /// @param tiersFinestFirst  signed-distance level sets, voxel sizes non-decreasing; see
    ///                          ShapeFields::ShapeFields for the requirements on each grid
    /// @param opts              options of the field computation, the same for every tier
    /// @throw openvdb::ValueError if a grid is null or invalid, or the tiers are not ordered
    /// finest first.
    FieldSampler(const std::vector<openvdb::FloatGrid::ConstPtr>& tiersFinestFirst,
                 const ShapeFieldOptions& opts);

    /// Stores precomputed fields; voxel sizes must be non-decreasing.
    /// @throw openvdb::ValueError if a pointer is null or the tiers are not ordered finest first.
    explicit FieldSampler(const std::vector<const ShapeFields<D>*>& tiersFinestFirst,
                          bool threaded = true);

    /// The tiers of @a samplersFinestFirst, in that order, shared with them (not copied):
    /// a sampler that reuses tiers built for another level.
    /// @throw openvdb::ValueError if a pointer is null or the tiers are not ordered finest first.
    explicit FieldSampler(const std::vector<ConstPtr>& samplersFinestFirst);

    /// Same as the constructor taking grids.
    static Ptr build(const std::vector<openvdb::FloatGrid::ConstPtr>& tiersFinestFirst,
                     const ShapeFieldOptions& opts)
    {
        return std::make_shared<FieldSampler>(tiersFinestFirst, opts);
    }

    size_t tierCount() const { return mTiers.size(); }
    /// Voxel size h of a tier, Omega units.
    Real voxelSize(size_t tier) const { return mTiers[tier]->h; }
    /// Number of stored blocks of a tier.
    size_t blockCount(size_t tier) const { return mTiers[tier]->blocks; }
    /// Bytes used by the stored fields, block tables and flags.
    size_t memoryUsage() const;

    /// Index of the tier a query at x uses, or -1 if no tier covers x.
    int findTier(const Vec<D>& x) const;

    /// Interpolated signed distance only (cheap). Returns false if no tier covers x. The value
    /// is bitwise identical to the d returned by sample() at the same x.
    bool sampleDistance(const Vec<D>& x, Real& d) const;
    /// As above, and the voxel size of the tier used (Omega units).
    bool sampleDistance(const Vec<D>& x, Real& d, Real* tierVoxelSize) const;
    /// As above, and the index of the tier used (for sameStencil()).
    bool sampleDistance(const Vec<D>& x, Real& d, int& tierIndex) const;

    /// True if a query at x uses tier @a tierIndex with the same 3^D nodes as a query at @a x0
    /// that used that tier: every tier up to it rounds x and x0 to the same node. The
    /// interpolated d is then one quadratic polynomial on the segment from x0 to x, and along
    /// each axis its slope is a convex combination of the differences of adjacent node values
    /// divided by the voxel size (at most 1 for exact distances), so
    /// |d(x) - d(x0)| <= sqrt(D) max_a max |d_{i+e_a} - d_i| / h |x - x0|.
    bool sameStencil(const Vec<D>& x, const Vec<D>& x0, int tierIndex) const;

    /// Interpolated d, n, R at x and, if @a deriv is not null, their derivatives. Returns false
    /// (leaving the outputs untouched) if no tier covers x. No allocation.
    bool sample(const Vec<D>& x, RawFields<D>& fields, RawFieldDerivatives<D>* deriv) const;

private:
    struct Tier
    {
        Real h = 0;
        Real invH = 0;
        size_t blocks = 0;
        detail::DenseBlockTable table;
        std::vector<float> values;     ///< APRON_NODES * NUM_COMPONENTS per block
        std::vector<uint8_t> complete; ///< BLOCK_NODES per block
    };

    /// First float of the stencil's corner node and t per axis, or nullptr.
    const float* locate(const Vec<D>& x, Real* t, int& tier) const;
    void addTier(const ShapeFields<D>& fields, bool threaded);
    void checkOrder(Real h) const;

    std::vector<std::shared_ptr<const Tier>> mTiers;
};

extern template class FieldSampler<2>;
extern template class FieldSampler<3>;

} // namespace vdbmatch
