/// @file SurfaceProbe.h
/// @brief phi at fixed points of the source surface M1, as a fixed linear function of the nodal
///        displacements: what the descent watches to tell whether the match has settled.
///
/// On a lattice that does not change during a level, phi(x) = x + sum_m lambda_m u(v_m) for the
/// D+1 nodes v_m of the simplex containing x and its barycentric weights lambda_m
/// (multiscale::PiecewiseLinearInterpolator::locate gives them). The probe stores these per
/// point, so evaluating phi on tens of thousands of surface points costs a few vector operations
/// per iteration.
///
/// The surface test of Descent (DescentOptions::surfaceTolerance) sums the mean motion of these
/// points over the last w iterations: sum_j mean_x |phi_j(x) - phi_{j-1}(x)|. The late iterations
/// of a fine level lower the energy in its fourth digit by relaxing the deformation across the
/// narrow band, while the map on M1, which is what a user takes away, no longer moves
/// (docs/performance.md).
#pragma once

#include <vdbmatch/Types.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vdbmatch {
namespace solver {

template <int D> class SurfaceProbe
{
public:
    /// Appends a point by its simplex nodes and barycentric weights (summing to 1).
    void add(const std::array<int32_t, D + 1>& nodes, const std::array<Real, D + 1>& weights)
    {
        mNodes.push_back(nodes);
        mWeights.push_back(weights);
    }

    std::size_t size() const { return mNodes.size(); }
    bool empty() const { return mNodes.empty(); }

    /// The displacement u at every point (D x size()), from nodal displacements u (D x nodes).
    void displacements(const NodeVectors<D>& u, NodeVectors<D>& out) const
    {
        out.resize(D, Eigen::Index(size()));
        for (std::size_t i = 0; i < size(); ++i) {
            Vec<D> v = Vec<D>::Zero();
            for (int m = 0; m <= D; ++m)
                v += mWeights[i][m] * u.col(mNodes[i][m]);
            out.col(Eigen::Index(i)) = v;
        }
    }

    /// mean_i |a_i - b_i| over the points (0 if there are none).
    static Real meanDistance(const NodeVectors<D>& a, const NodeVectors<D>& b)
    {
        if (a.cols() == 0) return 0;
        return (a - b).colwise().norm().sum() / Real(a.cols());
    }

private:
    std::vector<std::array<int32_t, D + 1>> mNodes;
    std::vector<std::array<Real, D + 1>> mWeights;
};

} // namespace solver
} // namespace vdbmatch
