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

#include <vdbmatch/energy/ProjectedDensity.h>

namespace vdbmatch {
namespace energy {

/// c eta1 W(T2+ A T1- + n2 (x) n1), eq:Fbenddirect.
template <int D, bool Grad>
inline Real
bendingDirect(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
              DensityGradient<D>* grad)
{
    Mat<D> dTp2;
    const Real e = projectedDirect<D, Grad>(k, g, g.f2.Tp, g.f1.Tm, c, 0.0, grad, &dTp2);
    if constexpr (Grad) grad->f2.Tp += dTp2;
    return e;
}

/// c eta2 W(T1+ B T2- + n1 (x) n2) J, eq:Fbendinverse, for J > 0.
template <int D, bool Grad>
inline Real
bendingInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, Real c,
               DensityGradient<D>* grad)
{
    Mat<D> dTm2;
    const Real e = projectedInverse<D, Grad>(k, g, g.f1.Tp, g.f2.Tm, c, 0.0, grad, &dTm2);
    if constexpr (Grad) grad->f2.Tm += dTm2;
    return e;
}

} // namespace energy
} // namespace vdbmatch
