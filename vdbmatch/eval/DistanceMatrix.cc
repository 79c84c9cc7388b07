/// @file DistanceMatrix.cc
#include "DistanceMatrix.h"

#include <Eigen/Eigenvalues>
#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vdbmatch {
namespace eval {

DistanceMatrix
cleanedDistances(const DistanceMatrix& m)
{
    const std::size_t n = std::size_t(std::max(0, m.n));
    if (m.d.size() != n * n)
        OPENVDB_THROW(openvdb::ValueError,
                      "DistanceMatrix: " << m.d.size() << " entries for n = " << m.n);
    double largest = 0;
    for (double v : m.d) {
        if (std::isnan(v)) continue;
        if (!std::isfinite(v) || v < 0)
            OPENVDB_THROW(openvdb::ValueError,
                          "DistanceMatrix: entry " << v << " is not a distance");
        largest = std::max(largest, v);
    }
    DistanceMatrix out = m;
    for (std::size_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < n; ++j) {
            double a = m.d[i * n + j], b = m.d[j * n + i];
            a = std::isnan(a) ? largest : a;
            b = std::isnan(b) ? largest : b;
            out.d[i * n + j] = i == j ? 0.0 : 0.5 * (a + b);
        }
    }
    return out;
}

std::vector<int>
clusterOrder(const DistanceMatrix& input)
{
    const DistanceMatrix m = cleanedDistances(input);
    const int n = m.n;
    // Active clusters: their members in leaf order, and the sum of distances between clusters.
    std::vector<std::vector<int>> members(static_cast<std::size_t>(n), std::vector<int>());
    std::vector<bool> alive(std::size_t(n), true);
    std::vector<double> sum(std::size_t(n) * std::size_t(n));
    for (int i = 0; i < n; ++i) {
        members[std::size_t(i)] = {i};
        for (int j = 0; j < n; ++j)
            sum[std::size_t(i) * std::size_t(n) + std::size_t(j)] = m.at(i, j);
    }
    auto S = [&](int a, int b) -> double& {
        return sum[std::size_t(a) * std::size_t(n) + std::size_t(b)];
    };
    for (int step = 1; step < n; ++step) {
        int bestA = -1, bestB = -1;
        double best = std::numeric_limits<double>::infinity();
        for (int a = 0; a < n; ++a) {
            if (!alive[std::size_t(a)]) continue;
            for (int b = a + 1; b < n; ++b) {
                if (!alive[std::size_t(b)]) continue;
                const double mean = S(a, b) / double(members[std::size_t(a)].size() *
                                                     members[std::size_t(b)].size());
                if (mean < best) {
                    best = mean;
                    bestA = a;
                    bestB = b;
                }
            }
        }
        // Merge b into a (a < b, and a cluster is indexed by its smallest member, so a's
        // smallest index is the smaller one and its members come first).
        auto& ma = members[std::size_t(bestA)];
        auto& mb = members[std::size_t(bestB)];
        ma.insert(ma.end(), mb.begin(), mb.end());
        mb.clear();
        alive[std::size_t(bestB)] = false;
        for (int c = 0; c < n; ++c) {
            if (!alive[std::size_t(c)] || c == bestA) continue;
            S(bestA, c) += S(bestB, c);
            S(c, bestA) = S(bestA, c);
        }
    }
    return n > 0 ? members[0] : std::vector<int>();
}

std::vector<Vec<2>>
classicalMds(const DistanceMatrix& input)
{
    const DistanceMatrix m = cleanedDistances(input);
    const int n = m.n;
    std::vector<Vec<2>> out(std::size_t(n), Vec<2>::Zero());
    if (n < 2) return out;
    Eigen::MatrixXd B(n, n);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            B(i, j) = -0.5 * m.at(i, j) * m.at(i, j);
    // Double centring: B = J B J.
    const Eigen::VectorXd rowMean = B.rowwise().mean();
    const Eigen::VectorXd colMean = B.colwise().mean().transpose();
    const double mean = B.mean();
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            B(i, j) += mean - rowMean[i] - colMean[j];
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(B);
    // Eigen sorts the eigenvalues in increasing order: the two leading ones are last.
    for (int axis = 0; axis < 2 && axis < n; ++axis) {
        const int k = n - 1 - axis;
        const double scale = std::sqrt(std::max(0.0, eig.eigenvalues()[k]));
        Eigen::VectorXd v = eig.eigenvectors().col(k);
        Eigen::Index big = 0;
        v.cwiseAbs().maxCoeff(&big);
        if (v[big] < 0) v = -v;
        for (int i = 0; i < n; ++i)
            out[std::size_t(i)][axis] = scale * v[i];
    }
    return out;
}

} // namespace eval
} // namespace vdbmatch
