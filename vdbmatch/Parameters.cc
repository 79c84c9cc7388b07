/// @file Parameters.cc
#include "Parameters.h"

#include <openvdb/Exceptions.h>

#include <cmath>
#include <sstream>

namespace vdbmatch {

std::string
toString(EnergyKind kind)
{
    return kind == EnergyKind::Symmetric ? "symmetric" : "directional";
}

EnergyKind
parseEnergyKind(const std::string& name)
{
    if (name == "symmetric") return EnergyKind::Symmetric;
    if (name == "directional") return EnergyKind::Directional;
    OPENVDB_THROW(openvdb::ValueError,
                  "parseEnergyKind: expected \"symmetric\" or \"directional\", got \"" << name
                                                                                       << "\"");
}

EnergyParameters
EnergyParameters::defaults(int dim)
{
    EnergyParameters p;
    if (dim == 2) { // tab:parameters, Jump
        p.cMatch = 0.512;
        p.cVol = 0.8;
        p.cMem = 1.0;
        p.cBend = 1.0;
        p.q = 3.0;
        p.theta = 1.0;
    } else if (dim == 3) { // tab:parameters, Dolphin and Starfish
        p.cMatch = 4.096;
        p.cVol = 0.8;
        p.cMem = 1.0;
        p.cBend = 0.2;
        p.q = 4.0;
        p.theta = 1.0;
    } else {
        OPENVDB_THROW(openvdb::ValueError,
                      "EnergyParameters::defaults: dimension must be 2 or 3, got " << dim);
    }
    return p;
}

void
EnergyParameters::validate() const
{
    auto nonNegative = [](const char* name, Real v) {
        if (!std::isfinite(v) || v < 0)
            OPENVDB_THROW(openvdb::ValueError,
                          "EnergyParameters: " << name << " must be finite and >= 0, got " << v);
    };
    nonNegative("c_match", cMatch);
    nonNegative("c_mem", cMem);
    nonNegative("c_bend", cBend);
    nonNegative("c_vol", cVol);
    auto inRange = [](const char* name, Real v, Real lo, Real hi) {
        if (!(v >= lo && v <= hi))
            OPENVDB_THROW(openvdb::ValueError, "EnergyParameters: " << name << " must be in [" << lo
                                                                    << ", " << hi << "], got "
                                                                    << v);
    };
    inRange("c_match", cMatch, 0, MAX_COEFFICIENT);
    inRange("c_mem", cMem, 0, MAX_COEFFICIENT);
    inRange("c_bend", cBend, 0, MAX_COEFFICIENT);
    inRange("c_vol", cVol, 0, MAX_COEFFICIENT);
    inRange("q", q, 0, MAX_EXPONENT);
    inRange("theta", theta, 0, MAX_EXPONENT);
    inRange("membrane saturation", membraneSaturation, 0, MAX_COEFFICIENT);
    if (!std::isfinite(tau) || tau <= 0)
        OPENVDB_THROW(openvdb::ValueError,
                      "EnergyParameters: tau must be finite and > 0, got " << tau);
    if (!std::isfinite(sigmaFactor) || sigmaFactor <= 0)
        OPENVDB_THROW(openvdb::ValueError,
                      "EnergyParameters: sigma factor must be finite and > 0, got " << sigmaFactor);
}

double
noiseBendingFactor(int noisePasses, double P)
{
    if (!(P > 0) || noisePasses <= 0) return 1.0;
    return 1.0 / (1.0 + double(noisePasses) / P);
}

} // namespace vdbmatch
