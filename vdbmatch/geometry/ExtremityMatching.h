/// @file ExtremityMatching.h
/// @brief Which extremity of one shape corresponds to which of the other (Extremities.h): the
///        pairing that best keeps the inner distances between them, for automatic landmarks (an
///        addition to the paper; docs/numerics.md "Automatic landmarks").
///
/// For k extremities a_i of M1 and b_j of M2 (the same count, 2 <= k <= MAX_EXTREMITIES), every
/// permutation pi is scored by its distortion of the inner distances A_ij, B_ij,
///
///   c(pi) = sum_{i<j} |A_ij - B_pi(i)pi(j)| / (1/2 sum_{i<j} (A_ij + B_ij)),
///
/// which an articulated (near-isometric) motion keeps small whatever the pose. A shape with a
/// symmetry (left and right arms, the five arms of a starfish) has several permutations of
/// nearly the same distortion; among those within `tolerance` of the least, the one that moves
/// the points least, min sum_i |a_i - b_pi(i)|^2, is taken (the shapes share one placement in
/// Omega, so left stays left). The pairing is refused when the counts differ or the least
/// distortion exceeds `maxDistortion`: the two shapes do not have the same branches.
/// Both scores are symmetric in the two shapes, so matching M2 to M1 gives the inverse pairing
/// (up to rounding of exact ties).
#pragma once

#include <vdbmatch/geometry/Extremities.h>

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace vdbmatch {

/// Options of matchExtremities().
struct ExtremityMatchOptions
{
    double maxDistortion = 0.25; ///< largest accepted c(pi)
    double tolerance = 0.035;    ///< permutations within this of the least c(pi) are candidates
};

/// Most extremities matchExtremities() pairs (k! permutations are scored).
constexpr std::size_t MAX_EXTREMITIES = 8;

/// The pairing of two sets of extremities.
struct ExtremityPairing
{
    bool ok = false;
    std::string reason; ///< why not, when !ok
    /// (index in the first set, index in the second), in the order of the first set.
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    double distortion = 0;      ///< c(pi) of the pairing taken
    double leastDistortion = 0; ///< min c over all permutations
    std::size_t candidates = 0; ///< permutations within the tolerance of the least
};

/// Pairs the extremities of two shapes (see the file comment).
/// @throw openvdb::ValueError if an option is negative or not finite
template <int D>
ExtremityPairing matchExtremities(const Extremities<D>& a, const Extremities<D>& b,
                                  const ExtremityMatchOptions& opts = ExtremityMatchOptions());

extern template ExtremityPairing matchExtremities<2>(const Extremities<2>&, const Extremities<2>&,
                                                     const ExtremityMatchOptions&);
extern template ExtremityPairing matchExtremities<3>(const Extremities<3>&, const Extremities<3>&,
                                                     const ExtremityMatchOptions&);

} // namespace vdbmatch
