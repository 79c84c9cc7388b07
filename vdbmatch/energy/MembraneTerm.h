/// @file MembraneTerm.h
/// @brief Membrane densities of eq:EsymMem: direct F_mem = W(P2 A P1 + n2 (x) n1)
///        (eq:Fmemdirect, weight eta_sigma(d1)) and inverse
///        𝓕_mem = W(P1 B P2 + n1 (x) n2) |det A| (eq:Fmeminverse, weight eta_sigma(d2 o phi)),
///        B = cof A^T / det A.
/// @see paper eq:EsymMem, eq:Fmemdirect, eq:Fmeminverse, eq:EdirMem
#pragma once

#include <vdbmatch/energy/SimplexState.h>
#include <vdbmatch/math/StoredEnergy.h>

namespace vdbmatch {
namespace energy {

/// c eta1 W(D_tt phi), eq:Fmemdirect.
template <int D, bool Grad>
inline Real
membraneDirect(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
               DensityGradient<D>* grad)
{
    const auto& f1 = g.f1;
    const auto& f2 = g.f2;
    const Mat<D> AP1 = k.A * f1.P;
    const Mat<D> X = f2.P * AP1 + f2.n * f1.n.transpose();
    const Real w = c * g.eta1;
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(X, G);
        G *= w;
        grad->dA += f2.P * G * f1.P;
        grad->f2.P += G * AP1.transpose();
        grad->f2.n += G * f1.n;
        return w * e;
    } else {
        return w * math::W<D>(X);
    }
}

/// c eta2 W(P1 B P2 + n1 (x) n2) J, eq:Fmeminverse, for J > 0.
template <int D, bool Grad>
inline Real
membraneInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
                DensityGradient<D>* grad)
{
    const auto& f1 = g.f1;
    const auto& f2 = g.f2;
    const Mat<D> P1B = f1.P * k.B;
    const Mat<D> X = P1B * f2.P + f1.n * f2.n.transpose();
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(X, G);
        const Real w = c * g.eta2 * k.J;
        G *= w;
        grad->dB += f1.P * G * f2.P;
        grad->f2.P += P1B.transpose() * G;
        grad->f2.n += G.transpose() * f1.n;
        grad->f2.d += c * g.eta2Derivative * k.J * e;
        grad->dA += (c * g.eta2 * e) * k.C;
        return w * e;
    } else {
        return c * g.eta2 * k.J * math::W<D>(X);
    }
}

} // namespace energy
} // namespace vdbmatch
