/// @file SameBits.h
/// @brief Bitwise equality of doubles, for the tests that check lane-by-lane arithmetic against
///        the per-simplex code it replaces (CellKinematics, CellBandTerms).
#pragma once

#include <vdbmatch/Types.h>

#include <cstring>

namespace vdbmatch {
namespace test {

/// The same double, bit for bit (also -0 against 0).
inline bool
sameBits(Real a, Real b)
{
    return std::memcmp(&a, &b, sizeof(Real)) == 0;
}

} // namespace test
} // namespace vdbmatch
