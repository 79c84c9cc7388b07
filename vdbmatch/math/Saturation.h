/// @file Saturation.h
/// @brief The membrane saturation, an addition to the paper: the membrane densities of
///        eq:EsymMem are taken through psi_s(w) = s log(1 + w/s) before their weights.
///
/// psi_s(0) = 0, psi_s'(0) = 1 and psi_s(w) <= w: small distortions cost what they cost in the
/// paper, large ones only logarithmically more. A convex density such as W of eq:Wbounded
/// spreads a joint's stretch over the whole surface (the spread costs less than the
/// concentrated stretch), so where a limb turns, the body slides along its own surface towards
/// it; a saturated density lets the stretch stay at the joint. psi_s is increasing and concave,
/// so psi_s o W is not polyconvex: the existence theory of the paper (sec:existence) does not
/// cover it, which is why match() applies it at the first levels only
/// (MultiscaleOptions::membraneSaturationLevels), and by default in 3D only
/// (DEFAULT_MATCH_MEMBRANE_SATURATION_3D). s = 0 means no saturation (psi = identity).
/// The inverse half saturates W before its factor |det D phi|, so the symmetry of eq:Esym
/// (direct half of one map = inverse half of its inverse, eq:inverseIntegral) holds as in the
/// paper.
/// @see paper eq:EsymMem, eq:Fmemdirect, eq:Fmeminverse, docs/numerics.md (Membrane saturation)
#pragma once

#include <vdbmatch/Types.h>

#include <cmath>

namespace vdbmatch {
namespace math {

/// psi_s(w) = s log(1 + w/s) for s > 0, w for s == 0 (w >= 0, finite).
inline Real
saturated(Real w, Real s)
{
    return s > 0 ? s * std::log1p(w / s) : w;
}

/// psi_s'(w) = s / (s + w) for s > 0, 1 for s == 0.
inline Real
saturatedSlope(Real w, Real s)
{
    return s > 0 ? s / (s + w) : 1.0;
}

} // namespace math
} // namespace vdbmatch
