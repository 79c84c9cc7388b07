/// @file VolumeTerm.h
/// @brief Volume densities: symmetric W(A) + W(cof A^T / det A)|det A| of eq:EsymVol and the
///        comparison density W_vol(A) of eq:EcomparisonVol. The factor c_vol sigma^theta is
///        passed in as c.
/// @see paper eq:EsymVol, eq:EcomparisonVol
#pragma once

#include <vdbmatch/energy/SimplexState.h>
#include <vdbmatch/math/StoredEnergy.h>

namespace vdbmatch {
namespace energy {

/// Direct half of eq:EsymVol: c W(A).
template <int D, bool Grad>
inline Real
volumeDirect(const SimplexKinematics<D>& k, Real c, DensityGradient<D>* grad)
{
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(k.A, k.J, k.C, G);
        grad->dA += c * G;
        return c * e;
    } else {
        return c * math::W<D>(k.A, k.J);
    }
}

/// Inverse half of eq:EsymVol: c W(B) J for J > 0, with B = A^{-1}.
template <int D, bool Grad>
inline Real
volumeInverse(const SimplexKinematics<D>& k, Real c, DensityGradient<D>* grad)
{
    if constexpr (Grad) {
        Mat<D> G;
        // det B = 1 / J and cof B = det B B^{-T} = A^T / J.
        const Real invJ = 1.0 / k.J;
        const Real e = math::W<D>(k.B, invJ, Mat<D>(k.A.transpose() * invJ), G);
        grad->dB += (c * k.J) * G;
        grad->dA += (c * e) * k.C;
        return c * e * k.J;
    } else {
        // The products in the order of the branch above (value() and valueAndGradient() give
        // the same bits).
        return c * math::W<D>(k.B, 1.0 / k.J) * k.J;
    }
}

/// Comparison volume density of eq:EcomparisonVol: c W_vol(A).
template <int D, bool Grad>
inline Real
volumeComparison(const SimplexKinematics<D>& k, Real c, DensityGradient<D>* grad)
{
    Mat<D> G;
    const Real e = math::volW<D>(k.A, G);
    if constexpr (Grad) grad->dA += c * G;
    return c * e;
}

} // namespace energy
} // namespace vdbmatch
