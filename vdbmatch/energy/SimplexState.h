/// @file SimplexState.h
/// @brief Everything the energy densities need on one simplex: the constant deformation gradient
///        A = D phi, its cofactor, determinant and inverse B = cof A^T / det A
///        (eq:inverseIntegral), the band weights and the two surface frames, plus the accumulators
///        of the derivatives.
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/kinematics/SurfaceFrame.h>
#include <vdbmatch/math/MatrixOps.h>

namespace vdbmatch {
namespace energy {

/// Kinematics of one simplex. Only meaningful for J > 0 (the assembly returns +inf otherwise).
template <int D> struct SimplexKinematics
{
    Mat<D> A; ///< D phi
    Mat<D> C; ///< cof A
    Mat<D> B; ///< A^{-1} = C^T / J
    Real J;   ///< det A

    SimplexKinematics() = default;
    explicit SimplexKinematics(const Mat<D>& a) : A(a), C(math::cof(a))
    {
        J = (A.col(0).transpose() * C.col(0)).value();
        B = C.transpose() / J;
    }
};

/// The geometry seen by one quadrature point x with deformed position y = phi(x).
template <int D> struct PointGeometry
{
    Real eta1 = 0;                  ///< eta_sigma(d1(x))
    Real eta2 = 0;                  ///< eta_sigma(d2(y))
    Real eta2Derivative = 0;        ///< eta_sigma'(d2(y))
    kinematics::SurfaceFrame<D> f1; ///< shape 1 at x
    kinematics::SurfaceFrame<D> f2; ///< shape 2 at y
};

/// Derivatives accumulated by the energy densities: with respect to A, and with respect to the
/// frame of shape 2 at y (mapped to dE/dy afterwards by kinematics::frameAdjoint).
template <int D> struct DensityGradient
{
    Mat<D> dA = Mat<D>::Zero();
    Mat<D> dB = Mat<D>::Zero(); ///< w.r.t. B = A^{-1}; folded into dA by finish()
    kinematics::FrameAdjoint<D> f2;

    /// Adds the contribution of dB to dA: dB = -B dA B, so dE/dA += -B^T (dE/dB) B^T.
    void finish(const SimplexKinematics<D>& k) { dA -= k.B.transpose() * dB * k.B.transpose(); }
};

} // namespace energy
} // namespace vdbmatch
