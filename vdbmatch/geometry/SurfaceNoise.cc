/// @file SurfaceNoise.cc
/// @brief The noise of a surface: the vertex reading (median normal part of the umbrella
///        vector's change) and the lattice reading (median roughness of the Hessian of its
///        signed distance on a lattice).
#include "SurfaceNoise.h"

#include <vdbmatch/geometry/DistanceField.h>

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace vdbmatch {

namespace {

/// Normal of an element, weighted by its measure (3D: twice the area, 2D: the length).
Vec<3>
elementNormal(const Surface<3>& s, const std::array<int32_t, 3>& e)
{
    return (s.points[e[1]] - s.points[e[0]]).cross(s.points[e[2]] - s.points[e[0]]);
}
Vec<2>
elementNormal(const Surface<2>& s, const std::array<int32_t, 2>& e)
{
    const Vec<2> t = s.points[e[1]] - s.points[e[0]];
    return Vec<2>(t[1], -t[0]);
}

template <int D>
double
noise(const Surface<D>& s)
{
    const size_t n = s.points.size();
    for (const auto& e : s.elements)
        for (int32_t i : e)
            if (i < 0 || size_t(i) >= n) return 0.0;

    // Undirected edges, each once.
    std::vector<std::pair<int32_t, int32_t>> edges;
    edges.reserve(s.elements.size() * (D == 3 ? 3 : 1));
    for (const auto& e : s.elements) {
        for (int a = 0; a < (D == 3 ? 3 : 1); ++a) {
            int32_t i = e[a], j = e[(a + 1) % D];
            if (i == j) continue;
            if (i > j) std::swap(i, j);
            edges.emplace_back(i, j);
        }
    }
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());

    // Structure tensor of the incident normals: its principal direction is the vertex normal,
    // whatever the elements' orientation.
    std::vector<Mat<D>> tensor(n, Mat<D>::Zero());
    for (const auto& e : s.elements) {
        const Vec<D> m = elementNormal(s, e);
        const Mat<D> t = m * m.transpose() / std::max(m.norm(), 1e-300);
        for (int32_t i : e)
            tensor[size_t(i)] += t;
    }

    // Vertex normals: the principal direction of the structure tensor, sign arbitrary.
    std::vector<Vec<D>> normal(n, Vec<D>::Zero());
    std::vector<char> hasNormal(n, 0);
    for (size_t v = 0; v < n; ++v) {
        if (!(tensor[v].norm() > 0)) continue;
        Eigen::SelfAdjointEigenSolver<Mat<D>> solver;
        solver.computeDirect(tensor[v]);
        normal[v] = solver.eigenvectors().col(D - 1);
        hasNormal[v] = 1;
    }

    // Umbrella vectors u(v) = v - mean of the neighbours.
    std::vector<Vec<D>> sum(n, Vec<D>::Zero());
    std::vector<int> count(n, 0);
    for (const auto& [i, j] : edges) {
        sum[size_t(i)] += s.points[size_t(j)];
        sum[size_t(j)] += s.points[size_t(i)];
        ++count[size_t(i)];
        ++count[size_t(j)];
    }
    std::vector<double> normalPart(n, 0.0); // n(v) . u(v)
    for (size_t v = 0; v < n; ++v)
        if (count[v] > 0) normalPart[v] = normal[v].dot(s.points[v] - sum[v] / double(count[v]));

    // r(v) = n(v).u(v) - mean of the neighbours' n(w).u(w), each neighbour's normal turned to
    // the side of n(v): zero where the normal parts are all alike (a sphere, a regular mesh).
    std::vector<double> neighbourSum(n, 0.0);
    std::vector<int> neighbourCount(n, 0);
    for (const auto& [i, j] : edges) {
        if (!hasNormal[size_t(i)] || !hasNormal[size_t(j)]) continue;
        const double side = normal[size_t(i)].dot(normal[size_t(j)]) < 0 ? -1.0 : 1.0;
        neighbourSum[size_t(i)] += side * normalPart[size_t(j)];
        neighbourSum[size_t(j)] += side * normalPart[size_t(i)];
        ++neighbourCount[size_t(i)];
        ++neighbourCount[size_t(j)];
    }
    std::vector<double> values;
    values.reserve(n);
    for (size_t v = 0; v < n; ++v) {
        if (!hasNormal[v] || neighbourCount[v] == 0) continue;
        const double value = std::abs(normalPart[v] - neighbourSum[v] / neighbourCount[v]);
        if (std::isfinite(value)) values.push_back(value);
    }
    if (values.empty()) return 0.0;
    const auto middle = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle;
}

/// Hessian of d at node c by second differences (the off-diagonal terms centred); false if a
/// node of the stencil is outside the band.
template <int D>
bool
hessianAt(const openvdb::FloatGrid::ConstAccessor& acc, const openvdb::Coord& c, double h,
          Mat<D>& hessian)
{
    auto value = [&](int dx, int dy, int dz, double& out) {
        float v;
        if (!acc.probeValue(c.offsetBy(dx, dy, dz), v)) return false;
        out = double(v);
        return true;
    };
    double centre;
    if (!value(0, 0, 0, centre)) return false;
    const double inv = 1.0 / (h * h);
    for (int a = 0; a < D; ++a) {
        openvdb::Coord e(0, 0, 0);
        e[a] = 1;
        double plus, minus;
        if (!value(e[0], e[1], e[2], plus) || !value(-e[0], -e[1], -e[2], minus)) return false;
        hessian(a, a) = (plus - 2.0 * centre + minus) * inv;
        for (int b = a + 1; b < D; ++b) {
            openvdb::Coord f(0, 0, 0);
            f[b] = 1;
            double pp, pm, mp, mm;
            if (!value(e[0] + f[0], e[1] + f[1], e[2] + f[2], pp) ||
                !value(e[0] - f[0], e[1] - f[1], e[2] - f[2], pm) ||
                !value(-e[0] + f[0], -e[1] + f[1], -e[2] + f[2], mp) ||
                !value(-e[0] - f[0], -e[1] - f[1], -e[2] - f[2], mm))
                return false;
            hessian(a, b) = hessian(b, a) = (pp - pm - mp + mm) * 0.25 * inv;
        }
    }
    return true;
}

template <int D>
double
latticeNoise(const Surface<D>& surface, int level, bool threaded)
{
    const double h = std::ldexp(1.0, -level);
    // Nodes within h of M need d on 5^D nodes around them (the Hessian's stencil at each of
    // their 3^D neighbours): |d| <= h + 2 sqrt(D) h < 5 h on all of them.
    openvdb::FloatGrid::Ptr band = distanceBand<D>(surface, level, 5.0, threaded);
    std::vector<openvdb::Coord> nodes;
    for (auto it = band->cbeginValueOn(); it; ++it)
        if (std::abs(double(*it)) < h) nodes.push_back(it.getCoord());
    std::sort(nodes.begin(), nodes.end()); // a fixed order, whatever the tree's traversal
    std::vector<double> rough(nodes.size(), -1.0);
    auto body = [&](const tbb::blocked_range<size_t>& range) {
        openvdb::FloatGrid::ConstAccessor acc = band->getConstAccessor();
        for (size_t n = range.begin(); n != range.end(); ++n) {
            const openvdb::Coord& c = nodes[n];
            Mat<D> centre, smoothed = Mat<D>::Zero(), hessian;
            if (!hessianAt<D>(acc, c, h, centre)) continue;
            // One [1,2,1]/4 pass along every axis, as ShapeFields smooths the Hessian.
            bool complete = true;
            const int kz = D == 3 ? 1 : 0;
            for (int dz = -kz; dz <= kz && complete; ++dz)
                for (int dy = -1; dy <= 1 && complete; ++dy)
                    for (int dx = -1; dx <= 1 && complete; ++dx) {
                        if (!hessianAt<D>(acc, c.offsetBy(dx, dy, dz), h, hessian)) {
                            complete = false;
                            break;
                        }
                        const double w = (dx == 0 ? 0.5 : 0.25) * (dy == 0 ? 0.5 : 0.25) *
                                         (D == 3 ? (dz == 0 ? 0.5 : 0.25) : 1.0);
                        smoothed += w * hessian;
                    }
            if (complete) rough[n] = (centre - smoothed).norm();
        }
    };
    const tbb::blocked_range<size_t> all(0, nodes.size(), 256);
    if (threaded)
        tbb::parallel_for(all, body);
    else
        body(all);
    std::vector<double> values;
    values.reserve(rough.size());
    for (double r : rough)
        if (r >= 0 && std::isfinite(r)) values.push_back(r);
    if (values.empty()) return 0.0;
    const auto middle = values.begin() + std::ptrdiff_t(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    return *middle * h * h;
}

template <int D>
NoiseReading
reading(const Surface<D>& surface, double vertexFactor, double latticeFactor, bool threaded)
{
    NoiseReading r;
    if (!(vertexFactor > 0)) return r;
    r.vertex = noise<D>(surface);
    if (latticeFactor > 0) r.lattice = latticeNoise<D>(surface, LATTICE_NOISE_LEVEL, threaded);
    r.length = std::max(vertexFactor * r.vertex, latticeFactor * r.lattice);
    return r;
}

} // namespace

double
correlatedNoise(const NoiseReading& reading)
{
    const double white = WHITE_NOISE_LATTICE_RATIO * reading.vertex;
    return std::sqrt(std::max(0.0, reading.lattice * reading.lattice - white * white));
}

template <>
NoiseReading
readNoise<2>(const Surface<2>& surface, double vertexFactor, double latticeFactor, bool threaded)
{
    return reading<2>(surface, vertexFactor, latticeFactor, threaded);
}

template <>
NoiseReading
readNoise<3>(const Surface<3>& surface, double vertexFactor, double latticeFactor, bool threaded)
{
    return reading<3>(surface, vertexFactor, latticeFactor, threaded);
}

template <>
double
latticeSurfaceNoise<2>(const Surface<2>& surface, int level, bool threaded)
{
    return latticeNoise<2>(surface, level, threaded);
}

template <>
double
latticeSurfaceNoise<3>(const Surface<3>& surface, int level, bool threaded)
{
    return latticeNoise<3>(surface, level, threaded);
}

template <>
double
surfaceNoise<2>(const Surface<2>& surface)
{
    return noise<2>(surface);
}

template <>
double
surfaceNoise<3>(const Surface<3>& surface)
{
    return noise<3>(surface);
}

} // namespace vdbmatch
