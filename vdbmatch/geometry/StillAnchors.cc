#include <vdbmatch/Parallel.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/StillAnchors.h>

#include <openvdb/Exceptions.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace vdbmatch {

namespace {

/// Cells of side @a cell holding point indices, for "is any point within r" queries.
template <int D> class PointHash
{
public:
    PointHash(const std::vector<Vec<D>>& points, double cell) : mPoints(points), mCell(cell) {}

    void insert(std::size_t i) { mCells[key(cellOf(mPoints[i]))].push_back(i); }

    /// Whether some inserted point lies within @a r (<= the cell side) of @a x.
    bool anyWithin(const Vec<D>& x, double r) const
    {
        const std::array<int64_t, D> c = cellOf(x);
        for (int s = 0; s < (D == 3 ? 27 : 9); ++s) {
            std::array<int64_t, D> n = c;
            int rest = s;
            for (int a = 0; a < D; ++a) {
                n[a] += rest % 3 - 1;
                rest /= 3;
            }
            const auto it = mCells.find(key(n));
            if (it == mCells.end()) continue;
            for (std::size_t j : it->second)
                if ((mPoints[j] - x).squaredNorm() <= r * r) return true;
        }
        return false;
    }

private:
    std::array<int64_t, D> cellOf(const Vec<D>& x) const
    {
        std::array<int64_t, D> c;
        for (int a = 0; a < D; ++a)
            c[a] = int64_t(std::floor(x[a] / mCell));
        return c;
    }
    static int64_t key(const std::array<int64_t, D>& c)
    {
        // Omega points lie in [0, 1]; with cells >= 2^-20 the indices fit in 21 bits each.
        int64_t k = 0;
        for (int a = 0; a < D; ++a)
            k = (k << 21) | ((c[a] + (int64_t(1) << 20)) & ((int64_t(1) << 21) - 1));
        return k;
    }

    const std::vector<Vec<D>>& mPoints;
    double mCell;
    std::unordered_map<int64_t, std::vector<std::size_t>> mCells;
};

/// The vertices of @a self around which @a other coincides with it (steps 1 and 2 of the file
/// comment), in index order.
template <int D>
std::vector<std::size_t>
coincidentVertices(const Surface<D>& self, const Surface<D>& other, const StillAnchorOptions& opts,
                   int level, std::size_t& onOther)
{
    const double h = std::ldexp(1.0, -level);
    // The band must reach the tolerance: at least 3 voxels (distanceBand's minimum).
    const double halfWidth =
        std::max(MIN_DISTANCE_HALF_WIDTH_VOXELS, std::ceil(opts.tolerance / h) + 2.0);
    const openvdb::FloatGrid::Ptr d = distanceBand<D>(other, level, halfWidth, opts.threaded);
    const std::vector<Vec<D>>& x = self.points;
    std::vector<char> on(x.size(), 0);
    // The distance at the vertices: trilinear in the band's index space (2D: on its layer
    // k = 0, where the weight of layer 1 is zero); off the band, its inactive values.
    const auto acc = d->getConstAccessor();
    for (std::size_t i = 0; i < x.size(); ++i) {
        const openvdb::Vec3d p(x[i][0] / h, x[i][1] / h, D == 3 ? x[i][D - 1] / h : 0.0);
        float v = 0;
        openvdb::tools::BoxSampler::sample(acc, p, v);
        on[i] = std::abs(double(v)) <= opts.tolerance;
        onOther += std::size_t(on[i]);
    }
    // Erode the vertices on the other shape by the radius: drop those with a vertex off it
    // within the radius.
    const double cell = std::max(opts.radius, 1e-6);
    PointHash<D> off(x, cell);
    for (std::size_t i = 0; i < x.size(); ++i)
        if (!on[i]) off.insert(i);
    std::vector<std::size_t> out;
    for (std::size_t i = 0; i < x.size(); ++i)
        if (on[i] && !off.anyWithin(x[i], opts.radius)) out.push_back(i);
    return out;
}

} // namespace

template <int D>
StillAnchors<D>
findStillAnchors(const Surface<D>& unitSource, const Surface<D>& unitTarget,
                 const StillAnchorOptions& opts)
{
    checkSurface(unitSource, "source");
    checkSurface(unitTarget, "target");
    if (!(opts.tolerance >= 0) || !std::isfinite(opts.tolerance)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "findStillAnchors: tolerance must be finite and >= 0, got "
                          << opts.tolerance);
    }
    if (!(opts.radius >= 0) || !std::isfinite(opts.radius)) {
        OPENVDB_THROW(openvdb::ValueError,
                      "findStillAnchors: radius must be finite and >= 0, got " << opts.radius);
    }
    StillAnchors<D> out;
    out.level = opts.level > 0 ? opts.level
                               : (D == 3 ? StillAnchorOptions::DEFAULT_LEVEL_3D
                                         : StillAnchorOptions::DEFAULT_LEVEL_2D);
    // The coincident vertices of both shapes, each against the other: the anchors are then
    // the same whichever shape is the source.
    std::vector<std::size_t> sourceCoincident, targetCoincident;
    const auto findSource = [&] {
        sourceCoincident =
            coincidentVertices(unitSource, unitTarget, opts, out.level, out.onTarget);
    };
    const auto findTarget = [&] {
        targetCoincident =
            coincidentVertices(unitTarget, unitSource, opts, out.level, out.targetOnSource);
    };
    detail::invokeBoth(opts.threaded, findSource, findTarget);
    out.coincident = sourceCoincident.size();
    out.targetCoincident = targetCoincident.size();
    std::vector<Vec<D>> candidates;
    for (const std::size_t i : sourceCoincident)
        candidates.push_back(unitSource.points[i]);
    for (const std::size_t i : targetCoincident)
        candidates.push_back(unitTarget.points[i]);
    out.vertices = unitSource.points.size();
    out.targetVertices = unitTarget.points.size();
    if (candidates.empty() || opts.count == 0) return out;

    // The same candidates, in the same order, whichever shape is the source: sorted by their
    // coordinates (lexicographic; duplicates removed).
    std::sort(candidates.begin(), candidates.end(), [](const Vec<D>& a, const Vec<D>& b) {
        return std::lexicographical_compare(a.data(), a.data() + D, b.data(), b.data() + D);
    });
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());

    // Farthest-point sampling from the first candidate; ties to the first.
    std::vector<double> nearest(candidates.size(), std::numeric_limits<double>::infinity());
    std::size_t next = 0;
    while (out.points.size() < std::min(opts.count, candidates.size())) {
        const Vec<D> p = candidates[next];
        out.points.push_back(p);
        std::size_t best = 0;
        double bestDistance = -1;
        for (std::size_t k = 0; k < candidates.size(); ++k) {
            nearest[k] = std::min(nearest[k], (candidates[k] - p).squaredNorm());
            if (nearest[k] > bestDistance) {
                bestDistance = nearest[k];
                best = k;
            }
        }
        if (!(bestDistance > 0)) break; // every candidate is already an anchor
        next = best;
    }
    return out;
}

template StillAnchors<2> findStillAnchors<2>(const Surface<2>&, const Surface<2>&,
                                             const StillAnchorOptions&);
template StillAnchors<3> findStillAnchors<3>(const Surface<3>&, const Surface<3>&,
                                             const StillAnchorOptions&);

} // namespace vdbmatch
