/// @file BandWeight.h
/// @brief The narrow-band kernel eta and eta_sigma(s) = eta(s/sigma)/sigma (subsec:symenergy).
///
/// Our choice: the biweight eta(s) = (15/16)(1 - s^2)^2 on [-1, 1], 0 outside. It is C^1 with
/// support [-1, 1] and integral 1, as the paper requires (eta in C^1_0, int eta = 1,
/// supp eta = [-1, 1]); a polynomial spline as used in eq:coupledExponents.
/// @see paper subsec:symenergy
#pragma once

#include <vdbmatch/Types.h>

namespace vdbmatch {

/// eta_sigma and its derivative.
class BandWeight
{
public:
    /// @param sigma  band half-width, > 0, in Omega units.
    explicit BandWeight(Real sigma) : mSigma(sigma), mInvSigma(1.0 / sigma) {}

    Real sigma() const { return mSigma; }

    /// eta(s) = 15/16 (1 - s^2)^2 for |s| < 1, else 0.
    static Real eta(Real s)
    {
        if (!(s > -1.0 && s < 1.0)) return 0.0;
        const Real a = 1.0 - s * s;
        return ETA_SCALE * a * a;
    }

    /// eta'(s) = -15/4 s (1 - s^2) for |s| < 1, else 0.
    static Real etaDerivative(Real s)
    {
        if (!(s > -1.0 && s < 1.0)) return 0.0;
        return -4.0 * ETA_SCALE * s * (1.0 - s * s);
    }

    /// eta_sigma(d) = eta(d/sigma)/sigma.
    Real operator()(Real d) const { return mInvSigma * eta(d * mInvSigma); }

    /// eta_sigma(d) and d/dd eta_sigma(d).
    Real operator()(Real d, Real& derivative) const
    {
        const Real s = d * mInvSigma;
        derivative = mInvSigma * mInvSigma * etaDerivative(s);
        return mInvSigma * eta(s);
    }

    /// True if d is strictly inside the band, i.e. eta_sigma(d) > 0.
    bool inBand(Real d) const { return d > -mSigma && d < mSigma; }

private:
    static constexpr Real ETA_SCALE = 15.0 / 16.0;
    Real mSigma, mInvSigma;
};

} // namespace vdbmatch
