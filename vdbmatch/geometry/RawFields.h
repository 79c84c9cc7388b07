/// @file RawFields.h
/// @brief The per-point geometry of one shape as the field sampler returns it: signed distance,
///        interpolated (not yet normalised) normal and S^{1/2}, and their spatial derivatives.
/// @see paper subsec:notation, eq:defSi
#pragma once

#include <vdbmatch/Types.h>

#include <array>

namespace vdbmatch {

/// Values of the interpolated node fields of a shape at one point x (Omega units).
template <int D> struct RawFields
{
    Real d;   ///< signed distance d_i(x), negative inside
    Vec<D> n; ///< interpolant of the node normals grad d_i / |grad d_i| (not unit length)
    Mat<D> R; ///< interpolant of the node matrices S_i^{1/2} (symmetric positive definite)
};

/// Spatial derivatives of the same interpolants, with respect to Omega coordinates.
template <int D> struct RawFieldDerivatives
{
    Vec<D> dd;                ///< grad d
    Mat<D> dn;                ///< dn(i, k) = d n_i / d x_k
    std::array<Mat<D>, D> dR; ///< dR[k] = d R / d x_k
};

} // namespace vdbmatch
