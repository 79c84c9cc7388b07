/// @file SurfaceNoise.cc
/// @brief The vertex noise of a surface: median normal part of the umbrella vector's change.
#include "SurfaceNoise.h"

#include <Eigen/Eigenvalues>

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

} // namespace

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
