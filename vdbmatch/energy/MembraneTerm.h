/// @file MembraneTerm.h
/// @brief Membrane densities of eq:EsymMem: direct F_mem = W(P2 A P1 + n2 (x) n1)
///        (eq:Fmemdirect, weight eta_sigma(d1)) and inverse
///        𝓕_mem = W(P1 B P2 + n1 (x) n2) |det A| (eq:Fmeminverse, weight eta_sigma(d2 o phi)),
///        B = cof A^T / det A. Optionally saturated, psi_s o W (math/Saturation.h, an addition).
/// @see paper eq:EsymMem, eq:Fmemdirect, eq:Fmeminverse, eq:EdirMem
#pragma once

#include <vdbmatch/energy/ProjectedDensity.h>

namespace vdbmatch {
namespace energy {

/// c eta1 psi_s(W(D_tt phi)), eq:Fmemdirect; s = 0 (no saturation) is the paper's.
template <int D, bool Grad>
inline Real
membraneDirect(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c, Real s,
               DensityGradient<D>* grad)
{
    Mat<D> dP2;
    const Real e = projectedDirect<D, Grad>(k, g, g.f2.P, g.f1.P, c, s, grad, &dP2);
    if constexpr (Grad) grad->f2.P += dP2;
    return e;
}

/// c eta2 psi_s(W(P1 B P2 + n1 (x) n2)) J, eq:Fmeminverse, for J > 0; s = 0 is the paper's.
template <int D, bool Grad>
inline Real
membraneInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c, Real s,
                DensityGradient<D>* grad)
{
    Mat<D> dP2;
    const Real e = projectedInverse<D, Grad>(k, g, g.f1.P, g.f2.P, c, s, grad, &dP2);
    if constexpr (Grad) grad->f2.P += dP2;
    return e;
}

} // namespace energy
} // namespace vdbmatch
