/// @file NearestPoints.h
/// @brief The nearest of a fixed set of points to a query point, exactly, by a balanced k-d tree.
///
/// The answer is the one a scan of the points in their order gives: the nearest, and of
/// equally near points the first (the lowest index), so that replacing such a scan by the tree
/// changes no result. The tree is built once (median splits along the widest extent of each
/// node's box, O(n log^2 n)); a query is O(log n) on well-spread points. Queries are const and
/// may run in parallel.
#pragma once

#include <vdbmatch/Types.h>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

namespace vdbmatch {

template <int D> class NearestPoints
{
public:
    explicit NearestPoints(std::vector<Vec<D>> points) : mPoints(std::move(points))
    {
        mOrder.resize(mPoints.size());
        for (std::size_t i = 0; i < mOrder.size(); ++i)
            mOrder[i] = i;
        mAxis.assign(mPoints.size(), 0);
        build(0, mOrder.size());
    }

    std::size_t size() const { return mPoints.size(); }

    /// The index (in the points given) of the point nearest @a x, the lowest of equally near
    /// ones, and its squared distance; (size(), +inf) when there are no points.
    std::pair<std::size_t, double> nearest(const Vec<D>& x) const
    {
        std::pair<std::size_t, double> best(mPoints.size(),
                                            std::numeric_limits<double>::infinity());
        search(0, mOrder.size(), x, best);
        return best;
    }

private:
    void build(std::size_t lo, std::size_t hi)
    {
        if (hi - lo < 2) return;
        Vec<D> low = mPoints[mOrder[lo]], high = low;
        for (std::size_t k = lo + 1; k < hi; ++k) {
            low = low.cwiseMin(mPoints[mOrder[k]]);
            high = high.cwiseMax(mPoints[mOrder[k]]);
        }
        int axis = 0;
        (high - low).maxCoeff(&axis);
        const std::size_t mid = lo + (hi - lo) / 2;
        std::nth_element(mOrder.begin() + std::ptrdiff_t(lo), mOrder.begin() + std::ptrdiff_t(mid),
                         mOrder.begin() + std::ptrdiff_t(hi), [&](std::size_t a, std::size_t b) {
                             const double pa = mPoints[a][axis], pb = mPoints[b][axis];
                             return pa < pb || (pa == pb && a < b);
                         });
        mAxis[mid] = axis;
        build(lo, mid);
        build(mid + 1, hi);
    }

    void search(std::size_t lo, std::size_t hi, const Vec<D>& x,
                std::pair<std::size_t, double>& best) const
    {
        if (lo >= hi) return;
        const std::size_t mid = lo + (hi - lo) / 2, i = mOrder[mid];
        const double d = (mPoints[i] - x).squaredNorm();
        if (d < best.second || (d == best.second && i < best.first)) best = {i, d};
        if (hi - lo == 1) return;
        const int axis = mAxis[mid];
        const double gap = x[axis] - mPoints[i][axis];
        // The near side first; the far side when it may hold a point as near (ties included).
        if (gap < 0) {
            search(lo, mid, x, best);
            if (gap * gap <= best.second) search(mid + 1, hi, x, best);
        } else {
            search(mid + 1, hi, x, best);
            if (gap * gap <= best.second) search(lo, mid, x, best);
        }
    }

    std::vector<Vec<D>> mPoints;
    std::vector<std::size_t> mOrder; ///< the points in tree order: node [lo, hi) has mid as root
    std::vector<int> mAxis;          ///< the split axis of the node whose root is at mid
};

} // namespace vdbmatch
