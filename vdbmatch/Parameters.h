/// @file Parameters.h
/// @brief Coefficients of the matching energy, paper tab:parameters, and their validation.
///
/// The energy at level l uses h = 2^{-l}, sigma = 2h (tab:parameters: sigma = 2^{-l+1}),
/// E = c_match E_match + c_mem E_mem + c_bend E_bend + c_vol E_vol with the volume term scaled by
/// sigma^theta (eq:EsymVol) and the matching term by sigma^{-q} (eq:EsymMatch).
/// @see paper tab:parameters, eq:Esym, eq:Ecomparison
#pragma once

#include <vdbmatch/Types.h>

#include <string>

namespace vdbmatch {

/// Which functional is minimised: the symmetric E^sigma of eq:Esym or the directional
/// comparison energy of eq:Ecomparison (direct halves only, with W_vol).
enum class EnergyKind { Symmetric, Directional };

/// "symmetric" / "directional".
std::string toString(EnergyKind kind);
/// Parses "symmetric" or "directional"; throws openvdb::ValueError otherwise.
EnergyKind parseEnergyKind(const std::string& name);

/// Largest energy coefficient (c_match, c_mem, c_bend, c_vol) accepted: the paper's are 0.2..4.1;
/// far larger ones only overflow the energy.
constexpr double MAX_COEFFICIENT = 1e6;
/// Largest exponent q or theta accepted: the weights sigma^-q and sigma^theta with sigma = 2^-8
/// already span 2^-64..2^64 at 8.
constexpr double MAX_EXPONENT = 8.0;

/// Default MatchOptions::noiseBendingPasses P (--noise-bending), an addition to the paper: at a
/// level where the noise smoothing gives a shape's distance Hessian n passes (the larger n of the
/// two shapes), eq:EsymBend weighs c_bend noiseBendingFactor(n, P) = c_bend / (1 + n / P). n = 0
/// on noise-free inputs, which keep the paper's weight bitwise. Measured on the benchmark's
/// scans (docs/numerics.md "Bending weight on noisy shapes"): where the Hessian had to be
/// smoothed, the bending term still costs correspondence; P = 4 halves c_bend where 4 passes
/// are needed (the 2D scans at level 7).
constexpr double DEFAULT_NOISE_BENDING_PASSES = 4;

/// The factor of c_bend for @a noisePasses Hessian smoothing passes: 1 / (1 + noisePasses / P),
/// and exactly 1 when P <= 0 (off) or noisePasses <= 0.
double noiseBendingFactor(int noisePasses, double P);

struct EnergyParameters
{
    Real cMatch = 4.096; ///< c_match
    Real cMem = 1.0;     ///< c_mem
    Real cBend = 0.2;    ///< c_bend
    Real cVol = 0.8;     ///< c_vol
    Real q = 4.0;        ///< matching exponent: weight sigma^{-q} (eq:EsymMatch)
    Real theta = 1.0;    ///< volume exponent: weight sigma^theta (eq:EsymVol), paper uses 0 or 1
    /// Eigenvalue floor of the regularised shape operator S = R(D^2 d + n (x) n), eq:defSi, in
    /// 1/Omega-units. Not listed in tab:parameters; 1 means curvature radii larger than the unit
    /// box are treated alike (flat). Same value as DEFAULT_SHAPE_OPERATOR_TAU (ShapeFields.h).
    Real tau = 1.0;
    /// Band half-width as a multiple of h: sigma = sigmaFactor * h (tab:parameters: 2).
    Real sigmaFactor = 2.0;
    /// Membrane saturation s, an addition to the paper: both membrane densities of eq:EsymMem
    /// are taken through psi_s(w) = s log(1 + w/s) (math/Saturation.h), which lets a joint's
    /// stretch stay at the joint instead of spreading over the surface. 0: the paper's W.
    Real membraneSaturation = 0.0;

    /// The defaults of tab:parameters for dimension 2 (Jump example) or 3 (Dolphin, Starfish).
    static EnergyParameters defaults(int dim);

    /// Throws openvdb::ValueError naming the first invalid field: coefficients must be finite
    /// in [0, MAX_COEFFICIENT], q and theta in [0, MAX_EXPONENT], tau > 0,
    /// sigmaFactor > 0, membraneSaturation finite in [0, MAX_COEFFICIENT].
    void validate() const;
};

} // namespace vdbmatch
