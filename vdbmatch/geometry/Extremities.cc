#include <vdbmatch/geometry/DenseLattice.h>
#include <vdbmatch/geometry/DistanceField.h>
#include <vdbmatch/geometry/Extremities.h>

#include <openvdb/openvdb.h>

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

/// The nodes of the dense lattice inside the shape and their neighbours.
template <int D> struct InteriorGraph
{
    int n = 0; ///< nodes per axis minus one (2^level)
    double h = 0;
    std::vector<float> distance;           ///< signed distance per dense node (band values)
    float background = 0;                  ///< |distance| off the band
    std::vector<int64_t> offsets;          ///< linear index offsets of the 3^D - 1 neighbours
    std::vector<std::array<int, D>> steps; ///< the same as lattice steps
    std::vector<double> lengths;           ///< h |offset|

    int64_t size() const { return int64_t(distance.size()); }
    bool inside(int64_t i) const { return distance[std::size_t(i)] < 0; }
    std::array<int, D> coords(int64_t i) const { return detail::DenseIndex<D>::coords(i, n); }
    Vec<D> position(int64_t i) const
    {
        const std::array<int, D> c = coords(i);
        Vec<D> p;
        for (int a = 0; a < D; ++a)
            p[a] = h * c[a];
        return p;
    }
    /// Calls visit(j, length) for every neighbour j of node i inside the shape.
    template <typename F> void forEachInsideNeighbour(int64_t i, F&& visit) const
    {
        const std::array<int, D> c = coords(i);
        for (std::size_t s = 0; s < steps.size(); ++s) {
            bool ok = true;
            for (int a = 0; a < D && ok; ++a) {
                const int x = c[a] + steps[s][a];
                ok = x >= 0 && x <= n;
            }
            if (!ok) continue;
            const int64_t j = i + offsets[s];
            if (inside(j)) visit(j, lengths[s]);
        }
    }
};

template <int D>
InteriorGraph<D>
interiorGraph(const Surface<D>& surface, int level, bool threaded)
{
    InteriorGraph<D> g;
    g.n = 1 << level;
    g.h = std::ldexp(1.0, -level);
    // A narrow band: its inactive values carry the sign inside (-background), and the depth
    // inside is found from it (depthInside()), far cheaper than the distance on the whole box.
    g.distance = detail::denseBandDistance<D>(surface, level, threaded, g.background);
    const int64_t m = g.n + 1;
    // The 3^D - 1 neighbours, in a fixed order.
    for (int s = 0; s < (D == 3 ? 27 : 9); ++s) {
        std::array<int, D> step;
        int rest = s, norm2 = 0;
        int64_t offset = 0, stride = 1;
        for (int a = 0; a < D; ++a) {
            step[a] = rest % 3 - 1;
            rest /= 3;
            norm2 += step[a] * step[a];
            offset += step[a] * stride;
            stride *= m;
        }
        if (norm2 == 0) continue;
        g.steps.push_back(step);
        g.offsets.push_back(offset);
        g.lengths.push_back(g.h * std::sqrt(double(norm2)));
    }
    return g;
}

/// Graph distances inside the shape from the nodes of @a sources, which start at their values
/// there (Dijkstra); infinity where unreachable.
template <int D>
std::vector<double>
innerDistances(const InteriorGraph<D>& g, const std::vector<std::pair<double, int64_t>>& sources)
{
    std::vector<double> dist(std::size_t(g.size()), std::numeric_limits<double>::infinity());
    using Entry = std::pair<double, int64_t>;
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> queue;
    for (const auto& [d0, i] : sources) {
        dist[std::size_t(i)] = d0;
        queue.emplace(d0, i);
    }
    while (!queue.empty()) {
        const auto [d, i] = queue.top();
        queue.pop();
        if (d > dist[std::size_t(i)]) continue;
        g.forEachInsideNeighbour(i, [&](int64_t j, double length) {
            const double dj = d + length;
            if (dj < dist[std::size_t(j)]) {
                dist[std::size_t(j)] = dj;
                queue.emplace(dj, j);
            }
        });
    }
    return dist;
}

template <int D>
std::vector<double>
innerDistances(const InteriorGraph<D>& g, int64_t source)
{
    return innerDistances(g, {{0.0, source}});
}

/// Depth of every node inside the shape: its distance to the surface within the band, and
/// beyond it that distance plus the graph distance to the band (an upper bound, close for the
/// lattice's 3^D - 1 neighbours).
template <int D>
std::vector<double>
depthInside(const InteriorGraph<D>& g, float background)
{
    std::vector<std::pair<double, int64_t>> band;
    for (int64_t i = 0; i < g.size(); ++i) {
        const float d = g.distance[std::size_t(i)];
        if (d < 0 && d > -background) band.emplace_back(-double(d), i);
    }
    return innerDistances(g, band);
}

/// Persistence of every local maximum of @a f over the superlevel-set filtration (see the file
/// comment): pairs (node, persistence), the global maximum with persistence max f.
template <int D>
std::vector<std::pair<int64_t, double>>
maximaPersistence(const InteriorGraph<D>& g, const std::vector<double>& f)
{
    std::vector<int64_t> order;
    for (int64_t i = 0; i < g.size(); ++i) {
        if (std::isfinite(f[std::size_t(i)])) order.push_back(i);
    }
    // Decreasing f, the lower index first among equals: a total order, so the result is unique.
    std::sort(order.begin(), order.end(), [&](int64_t a, int64_t b) {
        const double fa = f[std::size_t(a)], fb = f[std::size_t(b)];
        return fa != fb ? fa > fb : a < b;
    });
    std::vector<int64_t> parent(std::size_t(g.size()), -1), top(std::size_t(g.size()), -1);
    const auto find = [&](int64_t x) {
        while (parent[std::size_t(x)] != x) {
            parent[std::size_t(x)] = parent[std::size_t(parent[std::size_t(x)])];
            x = parent[std::size_t(x)];
        }
        return x;
    };
    std::vector<std::pair<int64_t, double>> maxima;
    for (const int64_t v : order) {
        parent[std::size_t(v)] = v;
        top[std::size_t(v)] = v;
        g.forEachInsideNeighbour(v, [&](int64_t u, double) {
            if (parent[std::size_t(u)] < 0) return; // not yet in the superlevel set
            const int64_t ru = find(u), rv = find(v);
            if (ru == rv) return;
            // The component whose maximum came first in the order survives.
            const int64_t tu = top[std::size_t(ru)], tv = top[std::size_t(rv)];
            const bool uFirst = f[std::size_t(tu)] != f[std::size_t(tv)]
                                    ? f[std::size_t(tu)] > f[std::size_t(tv)]
                                    : tu < tv;
            const int64_t keep = uFirst ? ru : rv, end = uFirst ? rv : ru;
            maxima.emplace_back(top[std::size_t(end)],
                                f[std::size_t(top[std::size_t(end)])] - f[std::size_t(v)]);
            parent[std::size_t(end)] = keep;
        });
    }
    if (!order.empty()) maxima.emplace_back(order.front(), f[std::size_t(order.front())]);
    return maxima;
}

} // namespace

template <int D>
Extremities<D>
findExtremities(const Surface<D>& unitSurface, const ExtremityOptions& opts)
{
    if (!(opts.minPersistence > 0 && opts.minPersistence <= 1)) {
        OPENVDB_THROW(openvdb::ValueError, "findExtremities: minPersistence must be in (0, 1], got "
                                               << opts.minPersistence);
    }
    Extremities<D> result;
    result.level = opts.level > 0 ? opts.level
                                  : (D == 3 ? ExtremityOptions::DEFAULT_LEVEL_3D
                                            : ExtremityOptions::DEFAULT_LEVEL_2D);
    const InteriorGraph<D> g = interiorGraph<D>(unitSurface, result.level, opts.threaded);

    // The root: among the nodes within h of the greatest depth, the one nearest to their
    // centroid (an elongated body has a ridge of deepest nodes: take its middle).
    const std::vector<double> depth = depthInside(g, g.background);
    double deepest = 0;
    for (int64_t i = 0; i < g.size(); ++i)
        if (g.inside(i) && std::isfinite(depth[std::size_t(i)]))
            deepest = std::max(deepest, depth[std::size_t(i)]);
    const auto isDeep = [&](int64_t i) {
        return g.inside(i) && std::isfinite(depth[std::size_t(i)]) &&
               depth[std::size_t(i)] >= deepest - g.h;
    };
    Vec<D> centroid = Vec<D>::Zero();
    std::size_t deep = 0;
    for (int64_t i = 0; i < g.size(); ++i) {
        if (isDeep(i)) {
            centroid += g.position(i);
            ++deep;
        }
    }
    int64_t root = -1;
    if (deep > 0) {
        centroid /= double(deep);
        double nearest = INF;
        for (int64_t i = 0; i < g.size(); ++i) {
            if (!isDeep(i)) continue;
            const double r = (g.position(i) - centroid).squaredNorm();
            if (r < nearest) {
                nearest = r;
                root = i;
            }
        }
    }
    if (root < 0) return result; // thinner than the lattice: no extremities (insideNodes = 0)
    result.root = g.position(root);
    const std::vector<double> f = innerDistances(g, root);
    std::vector<std::pair<int64_t, double>> maxima = maximaPersistence(g, f);
    result.maxRootDistance = maxima.back().second;
    result.insideNodes =
        std::size_t(std::count_if(f.begin(), f.end(), [](double x) { return std::isfinite(x); }));

    std::sort(maxima.begin(), maxima.end(), [](const auto& a, const auto& b) {
        return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    std::vector<int64_t> tips;
    const double rootDepth = depth[std::size_t(root)];
    for (const auto& [node, persistence] : maxima) {
        if (!(persistence >= opts.minPersistence * result.maxRootDistance)) break;
        tips.push_back(node);
        result.tips.push_back(g.position(node));
        result.persistence.push_back(persistence);
        // The end of the branch: the nodes connected to the tip with f >= f(tip) - rho.
        const double rho = std::min(0.5 * persistence, rootDepth);
        const double floor = f[std::size_t(node)] - rho;
        std::vector<int64_t> stack{node};
        Vec<D> sum = Vec<D>::Zero();
        std::vector<char> visited(std::size_t(g.size()), 0);
        visited[std::size_t(node)] = 1;
        std::size_t count = 0;
        while (!stack.empty()) {
            const int64_t v = stack.back();
            stack.pop_back();
            sum += g.position(v);
            ++count;
            g.forEachInsideNeighbour(v, [&](int64_t u, double) {
                if (visited[std::size_t(u)] || !(f[std::size_t(u)] >= floor)) return;
                visited[std::size_t(u)] = 1;
                stack.push_back(u);
            });
        }
        result.points.push_back(sum / double(count));
    }
    const std::size_t k = tips.size();
    result.innerDistance = Eigen::MatrixXd::Zero(Eigen::Index(k), Eigen::Index(k));
    for (std::size_t a = 0; a < k; ++a) {
        const std::vector<double> fa = innerDistances(g, tips[a]);
        for (std::size_t b = 0; b < k; ++b) {
            if (b != a)
                result.innerDistance(Eigen::Index(a), Eigen::Index(b)) = fa[std::size_t(tips[b])];
        }
    }
    // Dijkstra's sums differ in rounding between the two directions: use their mean.
    result.innerDistance = 0.5 * (result.innerDistance + result.innerDistance.transpose()).eval();
    return result;
}

template Extremities<2> findExtremities<2>(const Surface<2>&, const ExtremityOptions&);
template Extremities<3> findExtremities<3>(const Surface<3>&, const ExtremityOptions&);

} // namespace vdbmatch
