/// @file TestDistanceMatrix.cc
/// @brief eval::clusterOrder keeps tight groups contiguous; eval::classicalMds reproduces a
///        planar configuration from its distances; missing and asymmetric entries are cleaned.
#include <vdbmatch/eval/DistanceMatrix.h>

#include <gtest/gtest.h>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

using namespace vdbmatch;
using eval::DistanceMatrix;

namespace {

DistanceMatrix
fromPoints(const std::vector<Vec<2>>& p)
{
    DistanceMatrix m;
    m.n = int(p.size());
    for (const Vec<2>& a : p)
        for (const Vec<2>& b : p)
            m.d.push_back((a - b).norm());
    return m;
}

} // namespace

TEST(DistanceMatrix, ClusterOrderKeepsTightGroupsContiguous)
{
    // Two groups on a line, interleaved in the input: {0, 2, 4} near 0 and {1, 3} near 10.
    const DistanceMatrix m = fromPoints(
        {Vec<2>(0.0, 0), Vec<2>(10.0, 0), Vec<2>(0.1, 0), Vec<2>(10.2, 0), Vec<2>(0.25, 0)});
    const std::vector<int> order = eval::clusterOrder(m);
    ASSERT_EQ(order.size(), 5u);
    std::vector<int> sorted = order;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(sorted, (std::vector<int>{0, 1, 2, 3, 4}));
    // The first three are the group near 0 (the group holding index 0 comes first).
    std::vector<int> head(order.begin(), order.begin() + 3);
    std::sort(head.begin(), head.end());
    EXPECT_EQ(head, (std::vector<int>{0, 2, 4}));
}

TEST(DistanceMatrix, ClassicalMdsReproducesPlanarDistances)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-3, 3);
    std::vector<Vec<2>> p;
    for (int i = 0; i < 7; ++i)
        p.emplace_back(U(rng), U(rng));
    const DistanceMatrix m = fromPoints(p);
    const std::vector<Vec<2>> q = eval::classicalMds(m);
    ASSERT_EQ(q.size(), p.size());
    for (std::size_t i = 0; i < p.size(); ++i)
        for (std::size_t j = 0; j < p.size(); ++j)
            EXPECT_NEAR((q[i] - q[j]).norm(), m.at(int(i), int(j)), 1e-9);
}

TEST(DistanceMatrix, MissingEntriesCountAsFarAndTheMatrixIsSymmetrised)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    DistanceMatrix m;
    m.n = 3;
    m.d = {5, 1, nan, 3, 0, 4, nan, 4, 0};
    const DistanceMatrix c = eval::cleanedDistances(m);
    EXPECT_EQ(c.at(0, 0), 0);
    EXPECT_EQ(c.at(0, 1), 2); // (1 + 3) / 2
    EXPECT_EQ(c.at(1, 0), 2);
    EXPECT_EQ(c.at(0, 2), 5); // missing: the largest finite entry
    EXPECT_EQ(c.at(1, 2), 4);
}

TEST(DistanceMatrix, BadInputThrows)
{
    DistanceMatrix m;
    m.n = 2;
    m.d = {0, 1, 1};
    EXPECT_THROW(eval::clusterOrder(m), openvdb::ValueError);
    m.d = {0, -1, 1, 0};
    EXPECT_THROW(eval::classicalMds(m), openvdb::ValueError);
    m.d = {0, std::numeric_limits<double>::infinity(), 1, 0};
    EXPECT_THROW(eval::cleanedDistances(m), openvdb::ValueError);
    DistanceMatrix empty;
    EXPECT_TRUE(eval::clusterOrder(empty).empty());
    EXPECT_TRUE(eval::classicalMds(empty).empty());
}
