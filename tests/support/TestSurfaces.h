/// @file TestSurfaces.h
/// @brief Small explicit surfaces for tests: a unit cube, a UV sphere, circles, polygons and
/// squares, noise correlated over a few vertices, and a scratch directory per test.
#pragma once

#include <vdbmatch/geometry/Surface.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <system_error>
#include <unistd.h>
#include <vector>

namespace vdbmatch {
namespace test {

/// Moves every point of @a s along its radial direction from @a centre by a Gaussian field of
/// standard deviation sigma correlated over about @a passes edges: white N(0, 1) per vertex,
/// then @a passes times replaced by its mean over the vertex and its neighbours, then scaled
/// to standard deviation sigma. Seeded.
template <int D>
inline Surface<D>
correlatedNoise(Surface<D> s, const Vec<D>& centre, double sigma, int passes, unsigned seed)
{
    std::mt19937 random(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    std::vector<double> z(s.points.size());
    for (double& v : z)
        v = normal(random);
    std::vector<std::vector<int>> neighbours(s.points.size());
    for (const auto& e : s.elements)
        for (int a = 0; a < D; ++a)
            for (int b = 0; b < D; ++b)
                if (a != b) neighbours[size_t(e[a])].push_back(e[b]);
    for (auto& n : neighbours) {
        std::sort(n.begin(), n.end());
        n.erase(std::unique(n.begin(), n.end()), n.end());
    }
    for (int k = 0; k < passes; ++k) {
        std::vector<double> next(z.size());
        for (size_t v = 0; v < z.size(); ++v) {
            double sum = z[v];
            for (int w : neighbours[v])
                sum += z[size_t(w)];
            next[v] = sum / double(1 + neighbours[v].size());
        }
        z.swap(next);
    }
    double mean = 0, square = 0;
    for (double v : z)
        mean += v / double(z.size());
    for (double v : z)
        square += (v - mean) * (v - mean) / double(z.size());
    for (size_t v = 0; v < z.size(); ++v)
        s.points[v] +=
            sigma * (z[v] - mean) / std::sqrt(square) * (s.points[v] - centre).normalized();
    return s;
}

/// A closed polygon with n vertices on the ellipse centre + (a cos t, b sin t), counter-clockwise.
inline Surface<2>
ellipseCurve(const Vec<2>& centre, Real a, Real b, int n)
{
    Surface<2> s;
    for (int i = 0; i < n; ++i) {
        const Real t = 2 * M_PI * i / n;
        s.points.push_back(centre + Vec<2>(a * std::cos(t), b * std::sin(t)));
        s.elements.push_back({int32_t(i), int32_t((i + 1) % n)});
    }
    return s;
}

/// The cube [lo, lo + side]^3 as 12 outward-oriented triangles on 8 vertices.
inline Surface<3>
cubeMesh(double lo = 0.0, double side = 1.0)
{
    Surface<3> s;
    for (int k = 0; k < 8; ++k) {
        s.points.emplace_back(lo + side * (k & 1), lo + side * ((k >> 1) & 1),
                              lo + side * ((k >> 2) & 1));
    }
    // Quads (outward, counter-clockwise seen from outside), split into triangles.
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
        s.elements.push_back({q[0], q[1], q[2]});
        s.elements.push_back({q[0], q[2], q[3]});
    }
    return s;
}

/// A UV sphere with @a rings latitude bands and @a segments longitudes, outward-oriented.
inline Surface<3>
uvSphere(const Vec<3>& centre, double radius, int rings, int segments)
{
    Surface<3> s;
    s.points.push_back(centre + Vec<3>(0, 0, radius));
    for (int i = 1; i < rings; ++i) {
        const double theta = M_PI * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double phi = 2.0 * M_PI * j / segments;
            s.points.push_back(centre + radius * Vec<3>(std::sin(theta) * std::cos(phi),
                                                        std::sin(theta) * std::sin(phi),
                                                        std::cos(theta)));
        }
    }
    s.points.push_back(centre - Vec<3>(0, 0, radius));
    const int south = int(s.points.size()) - 1;
    auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
    for (int j = 0; j < segments; ++j) {
        s.elements.push_back({0, ring(1, j), ring(1, j + 1)});
        for (int i = 1; i + 1 < rings; ++i) {
            s.elements.push_back({ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)});
            s.elements.push_back({ring(i, j), ring(i + 1, j + 1), ring(i, j + 1)});
        }
        s.elements.push_back({south, ring(rings - 1, j + 1), ring(rings - 1, j)});
    }
    return s;
}

/// Appends a regular polygon with n vertices inscribed in a circle (counter-clockwise, or
/// clockwise if @a clockwise).
inline void
addCircle(Surface<2>& s, const Vec<2>& centre, double radius, int n, bool clockwise = false)
{
    const int first = int(s.points.size());
    for (int k = 0; k < n; ++k) {
        const double a = 2.0 * M_PI * k / n * (clockwise ? -1.0 : 1.0);
        s.points.push_back(centre + radius * Vec<2>(std::cos(a), std::sin(a)));
        s.elements.push_back({first + k, first + (k + 1) % n});
    }
}

/// A closed polygon through @a corners, each side cut in pieces of at most @a step.
inline Surface<2>
polygon(const std::vector<Vec<2>>& corners, double step)
{
    Surface<2> s;
    for (std::size_t k = 0; k < corners.size(); ++k) {
        const Vec<2> a = corners[k], b = corners[(k + 1) % corners.size()];
        const int n = std::max(1, int(std::ceil((b - a).norm() / step)));
        for (int i = 0; i < n; ++i)
            s.points.push_back(a + (b - a) * (double(i) / n));
    }
    const int32_t m = int32_t(s.points.size());
    for (int32_t i = 0; i < m; ++i)
        s.elements.push_back({i, (i + 1) % m});
    return s;
}

inline Surface<2>
circle(const Vec<2>& centre, double radius, int n)
{
    Surface<2> s;
    addCircle(s, centre, radius, n);
    return s;
}

/// A star polygon about @a centre: arm k ends at radius arms[k] in the direction
/// turn + 2 pi k / n, the notches between arms at radius @a inner; @a perEdge points per edge,
/// counter-clockwise.
inline Surface<2>
starCurve(const Vec<2>& centre, const std::vector<double>& arms, double inner, double turn,
          int perEdge = 24)
{
    const int n = int(arms.size());
    std::vector<Vec<2>> corners;
    for (int k = 0; k < n; ++k) {
        const double a = turn + 2 * M_PI * k / n, b = a + M_PI / n;
        corners.push_back(centre + arms[size_t(k)] * Vec<2>(std::cos(a), std::sin(a)));
        corners.push_back(centre + inner * Vec<2>(std::cos(b), std::sin(b)));
    }
    Surface<2> s;
    for (size_t c = 0; c < corners.size(); ++c) {
        const Vec<2>& p = corners[c];
        const Vec<2>& q = corners[(c + 1) % corners.size()];
        for (int i = 0; i < perEdge; ++i)
            s.points.push_back(p + (q - p) * (double(i) / perEdge));
    }
    const int m = int(s.points.size());
    for (int i = 0; i < m; ++i)
        s.elements.push_back({int32_t(i), int32_t((i + 1) % m)});
    return s;
}

/// Number of closed loops of a curve set (each vertex on two segments).
inline int
countLoops(const Surface<2>& s)
{
    std::vector<int> parent(s.points.size());
    for (size_t i = 0; i < parent.size(); ++i)
        parent[i] = int(i);
    auto find = [&](int i) {
        while (parent[size_t(i)] != i)
            i = parent[size_t(i)] = parent[size_t(parent[size_t(i)])];
        return i;
    };
    int loops = int(s.points.size());
    for (const auto& e : s.elements) {
        const int a = find(e[0]), b = find(e[1]);
        if (a != b) {
            parent[size_t(a)] = b;
            --loops;
        }
    }
    return loops;
}

/// A fresh directory under the system temp directory, named after the running test, removed at
/// destruction.
class ScratchDir
{
public:
    ScratchDir()
    {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        mPath = std::filesystem::temp_directory_path() /
                ("vdbmatch-" + std::string(info->test_suite_name()) + "-" + info->name() + "-" +
                 std::to_string(::getpid()));
        std::filesystem::remove_all(mPath);
        std::filesystem::create_directories(mPath);
    }
    ~ScratchDir()
    {
        std::error_code ec;
        std::filesystem::remove_all(mPath, ec);
    }
    std::string file(const std::string& name) const { return (mPath / name).string(); }
    const std::filesystem::path& path() const { return mPath; }

private:
    std::filesystem::path mPath;
};

} // namespace test
} // namespace vdbmatch
