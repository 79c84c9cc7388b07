/// @file StoredEnergy.h
/// @brief The stored energy densities of the paper: W of eq:Wbounded, the inverse-deformation
///        density W(cof A^T / det A)|det A| (subsec:storedenergy, eq:inverseIntegral) and the
///        comparison density W_vol of eq:EcomparisonVol, each with its derivative dW/dA.
///
/// @f[ W(A)=\tfrac{1}{d+1}|A|^{d+1} + \sqrt2\,d^{\frac{d-1}{2}}\sqrt{1+(\det A-2)^2}
///        - \tfrac{1}{d+1}d^{\frac{d+1}{2}} - 2d^{\frac{d-1}{2}} @f]
/// W is finite and C^1 on all of R^{dxd} (also for det A <= 0, as the paper requires for the
/// projected tangential derivative, subsec:tangential), W >= 0, W = 0 exactly on SO(d)
/// (lem:Wgeneral). The inverse density is +inf at det A = 0 and finite for det A != 0;
/// W_vol is +inf at det A = 0 and finite for det A < 0 (it only depends on det^2).
/// @see paper eq:Wgeneral, eq:Wbounded, eq:EcomparisonVol
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/math/MatrixOps.h>

#include <cmath>

namespace vdbmatch {
namespace math {

/// Constants of eq:Wbounded for dimension D.
template <int D> struct WboundedConstants
{
    /// sqrt(2) d^{(d-1)/2}
    static Real detCoefficient() { return std::sqrt(2.0) * std::pow(Real(D), 0.5 * (D - 1)); }
    /// 1/(d+1) d^{(d+1)/2} + 2 d^{(d-1)/2}, so that W(1) = 0.
    static Real offset()
    {
        return std::pow(Real(D), 0.5 * (D + 1)) / (D + 1) + 2.0 * std::pow(Real(D), 0.5 * (D - 1));
    }
};

/// |A|^{d+1} for d = 2, 3 without pow(): |A|^3 = s sqrt(s), |A|^4 = s^2 with s = |A|^2.
template <int D>
inline Real
frobeniusPowerDp1(Real s)
{
    if constexpr (D == 2)
        return s * std::sqrt(s);
    else
        return s * s;
}

/// |A|^{d-1} (the factor in d/dA |A|^{d+1}/(d+1) = |A|^{d-1} A).
template <int D>
inline Real
frobeniusPowerDm1(Real s)
{
    if constexpr (D == 2)
        return std::sqrt(s);
    else
        return s;
}

/// W of eq:Wbounded, given A and its determinant.
template <int D>
inline Real
W(const Mat<D>& A, Real detA)
{
    static const Real c = WboundedConstants<D>::detCoefficient();
    static const Real off = WboundedConstants<D>::offset();
    const Real s = A.squaredNorm();
    const Real t = detA - 2.0;
    return frobeniusPowerDp1<D>(s) / (D + 1) + c * std::sqrt(1.0 + t * t) - off;
}

/// W of eq:Wbounded, with det A by the Laplace expansion W(A, dW) uses (the same bits as the
/// energy of W(A, dW)).
template <int D>
inline Real
W(const Mat<D>& A)
{
    const Mat<D> C = cof(A);
    return W<D>(A, (A.col(0).transpose() * C.col(0)).value()); // Laplace expansion
}

/// W of eq:Wbounded and dW/dA = |A|^{d-1} A + sqrt2 d^{(d-1)/2} (det A - 2)/sqrt(1+(det A-2)^2) cof
/// A.
/// W of eq:Wbounded and dW/dA, given A with its determinant and cofactor matrix (for callers
/// that have them: the energy assembly knows det and cof of A and of A^{-1}).
template <int D>
inline Real
W(const Mat<D>& A, Real detA, const Mat<D>& cofA, Mat<D>& dW)
{
    static const Real c = WboundedConstants<D>::detCoefficient();
    static const Real off = WboundedConstants<D>::offset();
    const Real s = A.squaredNorm();
    const Real t = detA - 2.0;
    const Real r = std::sqrt(1.0 + t * t);
    dW = frobeniusPowerDm1<D>(s) * A + (c * t / r) * cofA;
    return frobeniusPowerDp1<D>(s) / (D + 1) + c * r - off;
}

template <int D>
inline Real
W(const Mat<D>& A, Mat<D>& dW)
{
    const Mat<D> C = cof(A);
    const Real detA = (A.col(0).transpose() * C.col(0)).value(); // Laplace expansion
    return W<D>(A, detA, C, dW);
}

/// Inverse-deformation density 𝒲(A) = W(cof A^T / det A) |det A| (subsec:storedenergy).
/// Returns +inf when det A == 0. For det A != 0 the derivative is
/// d𝒲/dA = -|det A| B^T W'(B) B^T + W(B) sign(det A) cof A with B = A^{-1} = cof A^T / det A.
template <int D>
inline Real
inverseW(const Mat<D>& A, Mat<D>& dW)
{
    const Mat<D> C = cof(A);
    const Real J = (A.col(0).transpose() * C.col(0)).value();
    if (J == 0.0) {
        dW.setZero();
        return INF;
    }
    const Mat<D> B = C.transpose() / J;
    Mat<D> dWB;
    const Real w = W<D>(B, dWB);
    const Real absJ = std::abs(J);
    dW = -absJ * (B.transpose() * dWB * B.transpose()) + (J > 0 ? w : -w) * C;
    return w * absJ;
}

template <int D>
inline Real
inverseW(const Mat<D>& A)
{
    Mat<D> dW;
    return inverseW<D>(A, dW);
}

/// Comparison volume density of eq:EcomparisonVol:
/// W_vol(A) = |A|^3 + |cof A|^3 + 3 (det A)^{-2} (d = 3), |A|^2 + (det A)^{-2} (d = 2).
/// +inf at det A = 0. W_vol(1) = 6 sqrt(3) + 3 (d = 3) and 3 (d = 2); the paper does not
/// subtract this constant and neither do we.
/// @note The paper states that 1 is stationary for W_vol. That holds for d = 2; for d = 3 as
///       printed, dW_vol(1) = (9 sqrt3 - 6) 1 (tested). The difference is a multiple of the
///       identity, i.e. a null Lagrangian direction: with phi = Id on the boundary of Omega,
///       sum_T |T| D phi_T is fixed, so phi = Id is still stationary for the integral of W_vol
///       (tested on the lattice). We implement the formula as printed.
template <int D>
inline Real
volW(const Mat<D>& A, Mat<D>& dW)
{
    const Mat<D> C = cof(A);
    const Real J = (A.col(0).transpose() * C.col(0)).value();
    if (J == 0.0) {
        dW.setZero();
        return INF;
    }
    const Real invJ2 = 1.0 / (J * J);
    if constexpr (D == 2) {
        // d/dA (det)^{-2} = -2 det^{-3} cof A
        dW = 2.0 * A - (2.0 * invJ2 / J) * C;
        return A.squaredNorm() + invJ2;
    } else {
        const Real a = A.norm(), c = C.norm();
        // d|A|^3 = 3|A| A; d|cof A|^3 = 3|cof A| cofAdjoint(cof A); d 3det^{-2} = -6 det^{-3} cof A
        dW = 3.0 * a * A + cofAdjoint<3>(A, 3.0 * c * C) - (6.0 * invJ2 / J) * C;
        return a * a * a + c * c * c + 3.0 * invJ2;
    }
}

template <int D>
inline Real
volW(const Mat<D>& A)
{
    Mat<D> dW;
    return volW<D>(A, dW);
}

} // namespace math
} // namespace vdbmatch
