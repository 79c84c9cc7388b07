/// @file BendingTerm.h
/// @brief Bending densities of eq:EsymBend: direct W(Lambda[S1, S2 o phi, A, n1, n2 o phi])
///        (eq:Fbenddirect, weight eta_sigma(d1)) and inverse
///        W(Lambda[S2 o phi, S1, B, n2 o phi, n1]) |det A| (eq:Fbendinverse, weight
///        eta_sigma(d2 o phi)).
///
/// With the tangential operators of kinematics::SurfaceFrame, T+ = P S^{1/2} P and
/// T- = P S^{-1/2} P: direct argument T2+ A T1- + n2 (x) n1, inverse argument
/// T1+ B T2- + n1 (x) n2.
/// @see paper eq:EsymBend, eq:lambdadef, eq:Fbenddirect, eq:Fbendinverse, eq:EdirBend
#pragma once

#include <vdbmatch/energy/SimplexState.h>
#include <vdbmatch/math/StoredEnergy.h>

namespace vdbmatch {
namespace energy {

/// c eta1 W(T2+ A T1- + n2 (x) n1), eq:Fbenddirect.
template <int D, bool Grad>
inline Real
bendingDirect(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
              DensityGradient<D>* grad)
{
    const auto& f1 = g.f1;
    const auto& f2 = g.f2;
    const Mat<D> AT1 = k.A * f1.Tm;
    const Mat<D> X = f2.Tp * AT1 + f2.n * f1.n.transpose();
    const Real w = c * g.eta1;
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(X, G);
        G *= w;
        grad->dA += f2.Tp.transpose() * G * f1.Tm.transpose();
        grad->f2.Tp += G * AT1.transpose();
        grad->f2.n += G * f1.n;
        return w * e;
    } else {
        return w * math::W<D>(X);
    }
}

/// c eta2 W(T1+ B T2- + n1 (x) n2) J, eq:Fbendinverse, for J > 0.
template <int D, bool Grad>
inline Real
bendingInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
               DensityGradient<D>* grad)
{
    const auto& f1 = g.f1;
    const auto& f2 = g.f2;
    const Mat<D> T1B = f1.Tp * k.B;
    const Mat<D> X = T1B * f2.Tm + f1.n * f2.n.transpose();
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(X, G);
        const Real w = c * g.eta2 * k.J;
        G *= w;
        grad->dB += f1.Tp.transpose() * G * f2.Tm.transpose();
        grad->f2.Tm += T1B.transpose() * G;
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
