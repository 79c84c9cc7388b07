/// @file Types.h
/// @brief Fixed-size Eigen types shared by the formula code, templated on the dimension d.
///
/// Space conventions used throughout vdbmatch:
/// - "Index" coordinates are integer lattice coordinates at the finest resolution of a level,
///   node i sits at x = i*h in the unit box Omega = (0,1)^d ("Omega" or "unit" coordinates).
/// - Signed distances are negative inside a shape (paper, subsec:notation).
/// - In 2D the third OpenVDB index coordinate is 0 and every 3-vector stored in a grid has z = 0.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

#include <limits>

namespace vdbmatch {

using Real = double;

template <int D> using Vec = Eigen::Matrix<Real, D, 1>;
template <int D> using Mat = Eigen::Matrix<Real, D, D>;

/// +infinity, the value of the energy for a simplex with det D(phi) <= 0.
constexpr Real INF = std::numeric_limits<Real>::infinity();

} // namespace vdbmatch
