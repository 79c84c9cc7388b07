/// @file ProjectedDensity.h
/// @brief The common shape of the membrane and bending densities: W(L A R + w (x) v), the direct
///        form (weight c eta1), and W(L B R + w (x) v) |det A| with B = A^{-1}, the inverse form
///        (weight c eta2), where L, R are tangential operators of the two shapes.
///
/// Membrane (eq:Fmemdirect, eq:Fmeminverse): L, R are the projections P2, P1 (direct) or
/// P1, P2 (inverse). Bending (eq:Fbenddirect, eq:Fbendinverse): P2 S2^{1/2} P2, P1 S1^{-1/2} P1
/// (direct) or P1 S1^{1/2} P1, P2 S2^{-1/2} P2 (inverse). In both forms, the operator of shape 2 is
/// the left one (direct) or the right one (inverse); its derivative is returned so that the caller
/// routes it to the frame member it came from. Both forms take W through the saturation psi_s
/// (math/Saturation.h, an addition to the paper; s = 0 for the paper's densities).
/// @see paper eq:Fmemdirect, eq:Fmeminverse, eq:Fbenddirect, eq:Fbendinverse, eq:lambdadef
#pragma once

#include <vdbmatch/energy/SimplexState.h>
#include <vdbmatch/math/Saturation.h>
#include <vdbmatch/math/StoredEnergy.h>

namespace vdbmatch {
namespace energy {

/// c eta1 psi_s(W(L2 A R1 + n2 (x) n1)). Adds d/dA to grad->dA and d/dn2 to grad->f2.n; returns
/// the density, and in @a dL2 the derivative with respect to the shape-2 operator L2.
template <int D, bool Grad>
inline Real
projectedDirect(const SimplexKinematics<D>& k, const PointGeometry<D>& g, const Mat<D>& L2,
                const Mat<D>& R1, Real c, Real s, DensityGradient<D>* grad, Mat<D>* dL2)
{
    const Mat<D> AR1 = k.A * R1;
    const Mat<D> X = L2 * AR1 + g.f2.n * g.f1.n.transpose();
    const Real w = c * g.eta1;
    if constexpr (Grad) {
        Mat<D> G;
        const Real e = math::W<D>(X, G);
        G *= s > 0 ? w * math::saturatedSlope(e, s) : w;
        grad->dA += L2.transpose() * G * R1.transpose();
        grad->f2.n += G * g.f1.n;
        *dL2 = G * AR1.transpose();
        return w * math::saturated(e, s);
    } else {
        (void)grad;
        (void)dL2;
        return w * math::saturated(math::W<D>(X), s);
    }
}

/// c eta2 psi_s(W(L1 B R2 + n1 (x) n2)) J for J = det A > 0. Adds d/dA (through B and J) to
/// grad, d/dn2 and d/dd2 (through eta2) to grad->f2; returns the density, and in @a dR2 the
/// derivative with respect to the shape-2 operator R2.
template <int D, bool Grad>
inline Real
projectedInverse(const SimplexKinematics<D>& k, const PointGeometry<D>& g, const Mat<D>& L1,
                 const Mat<D>& R2, Real c, Real s, DensityGradient<D>* grad, Mat<D>* dR2)
{
    const Mat<D> L1B = L1 * k.B;
    const Mat<D> X = L1B * R2 + g.f1.n * g.f2.n.transpose();
    if constexpr (Grad) {
        Mat<D> G;
        const Real w = math::W<D>(X, G);
        const Real e = math::saturated(w, s);
        G *= s > 0 ? c * g.eta2 * k.J * math::saturatedSlope(w, s) : c * g.eta2 * k.J;
        grad->dB += L1.transpose() * G * R2.transpose();
        grad->f2.n += G.transpose() * g.f1.n;
        grad->f2.d += c * g.eta2Derivative * k.J * e;
        grad->dA += (c * g.eta2 * e) * k.C;
        *dR2 = L1B.transpose() * G;
        return c * g.eta2 * k.J * e;
    } else {
        (void)grad;
        (void)dR2;
        return c * g.eta2 * k.J * math::saturated(math::W<D>(X), s);
    }
}

} // namespace energy
} // namespace vdbmatch
