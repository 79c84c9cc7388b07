/// @file MatchTerm.h
/// @brief Matching density of eq:EsymMatch:
///        sigma^{-q} (eta_sigma(d1) + eta_sigma(d2 o phi) |det D phi|) |d2 o phi - d1|^2.
///
/// The direct half (weight eta_sigma(d1)) is also the matching term of eq:EdirMatch used by the
/// directional energy eq:Ecomparison.
/// @see paper eq:EsymMatch, eq:EdirMatch
#pragma once

#include <vdbmatch/energy/SimplexState.h>

namespace vdbmatch {
namespace energy {

/// Direct half: c eta1 (d2 - d1)^2, with c = c_match sigma^{-q}. Returns the density.
template <int D, bool Grad>
inline Real
matchDirect(const PointGeometry<D>& g, Real c, DensityGradient<D>* grad)
{
    const Real r = g.f2.d - g.f1.d;
    if constexpr (Grad) grad->f2.d += 2.0 * c * g.eta1 * r;
    return c * g.eta1 * r * r;
}

/// Inverse half: c eta_sigma(d2) J (d2 - d1)^2 for J = det A > 0.
template <int D, bool Grad>
inline Real
matchInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
             DensityGradient<D>* grad)
{
    const Real r = g.f2.d - g.f1.d;
    const Real r2 = r * r;
    if constexpr (Grad) {
        grad->f2.d += c * k.J * (g.eta2Derivative * r2 + 2.0 * g.eta2 * r);
        grad->dA += (c * g.eta2 * r2) * k.C;
    }
    return c * g.eta2 * k.J * r2;
}

} // namespace energy
} // namespace vdbmatch
