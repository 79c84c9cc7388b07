/// @file TestNearestPoints.cc
/// @brief Tests of the exact nearest point (geometry/NearestPoints.h): on random points, on a
/// lattice full of equally near points and with repeated points, the tree gives what a scan of
/// the points in their order gives (the nearest, the first of equally near ones), in 2D and 3D.

#include <vdbmatch/geometry/NearestPoints.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

using namespace vdbmatch;

namespace {

template <int D>
std::pair<std::size_t, double>
scan(const std::vector<Vec<D>>& points, const Vec<D>& x)
{
    std::pair<std::size_t, double> best(points.size(), std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double d = (points[i] - x).squaredNorm();
        if (d < best.second) best = {i, d};
    }
    return best;
}

template <int D>
Vec<D>
randomPoint(std::mt19937& rng)
{
    std::uniform_real_distribution<double> u(0, 1);
    Vec<D> p;
    for (int k = 0; k < D; ++k)
        p[k] = u(rng);
    return p;
}

template <int D>
void
checkAgainstScan(const std::vector<Vec<D>>& points, const std::vector<Vec<D>>& queries)
{
    const NearestPoints<D> tree(points);
    ASSERT_EQ(tree.size(), points.size());
    for (const Vec<D>& x : queries) {
        const auto expected = scan(points, x), got = tree.nearest(x);
        ASSERT_EQ(got.first, expected.first) << x.transpose();
        ASSERT_EQ(got.second, expected.second) << x.transpose();
    }
}

template <int D>
void
checkAll()
{
    std::mt19937 rng(7);
    std::vector<Vec<D>> points, queries;
    for (int i = 0; i < 2000; ++i)
        points.push_back(randomPoint<D>(rng));
    for (int i = 0; i < 500; ++i)
        queries.push_back(randomPoint<D>(rng));
    checkAgainstScan(points, queries);

    // A lattice in shuffled order, queried at its points, at the centres of its cells (2^D points
    // equally near) and halfway along its edges (2 points equally near, one of them often on
    // the far side of a split, exactly as far as the split): the first of them in the points'
    // order is the answer.
    std::vector<Vec<D>> lattice, centres;
    const int n = D == 2 ? 20 : 8;
    for (int i = 0; i < int(std::pow(n, D)); ++i) {
        Vec<D> p, c;
        int r = i;
        for (int k = 0; k < D; ++k) {
            p[k] = double(r % n) / n;
            c[k] = (double(r % n) + 0.5) / n;
            r /= n;
        }
        lattice.push_back(p);
        centres.push_back(c);
        for (int k = 0; k < D; ++k) {
            Vec<D> e = p;
            e[k] += 0.5 / n;
            centres.push_back(e);
        }
    }
    std::shuffle(lattice.begin(), lattice.end(), rng);
    std::vector<Vec<D>> both = lattice;
    both.insert(both.end(), centres.begin(), centres.end());
    checkAgainstScan(lattice, both);

    // Repeated points: the first copy.
    std::vector<Vec<D>> repeated = lattice;
    repeated.insert(repeated.end(), lattice.begin(), lattice.end());
    checkAgainstScan(repeated, both);
}

} // namespace

TEST(NearestPoints, MatchesAScanIn2D)
{
    checkAll<2>();
}

TEST(NearestPoints, MatchesAScanIn3D)
{
    checkAll<3>();
}

TEST(NearestPoints, NoPoints)
{
    const NearestPoints<3> tree(std::vector<Vec<3>>{});
    const auto got = tree.nearest(Vec<3>(0.5, 0.5, 0.5));
    EXPECT_EQ(got.first, 0u);
    EXPECT_TRUE(std::isinf(got.second));
}
