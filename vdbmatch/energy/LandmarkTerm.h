/// @file LandmarkTerm.h
/// @brief Optional soft landmark term, an addition to the paper's energy (eq:Esym and
///        eq:Ecomparison have none): pairs of points a_k on M1 and b_k on M2 that the user
///        knows correspond, for what no shape energy can tell apart (a rotated disc, the left
///        and right arm of a figure whose pose changed a lot).
///
/// @f[ E_{\mathrm{lm}}[\phi] = \frac{c_{\mathrm{lm}}}{K} \sum_{k=1}^K |\phi(a_k) - b_k|^2 @f]
/// in Omega units, or sum_k w_k |phi(a_k) - b_k|^2 with per-pair weights (two sets of different
/// weights in one term: the automatic landmarks and anchors of match()). On a level's lattice
/// phi(a_k) = a_k + sum_m lambda_km u(v_km), the P1 interpolant on the Kuhn simplex containing a_k
/// (multiscale::PiecewiseLinearInterpolator), a fixed linear function of the nodal displacements:
/// the term is quadratic in u and its gradient, 2 c_lm / K (phi(a_k) - b_k) lambda_km at node v_km,
/// is exact.
///
/// Only the direct residual is penalised, also for the symmetric energy: when the constraint
/// holds, phi(a_k) = b_k, the inverse satisfies phi^{-1}(b_k) = a_k as well, so a run from M2 to
/// M1 with the landmark files swapped pulls towards the same correspondence. The weight does
/// not depend on the level: at coarse levels a landmark moves a whole coarse cell, at fine ones
/// the match term (weighted sigma^{-q}) dominates near the surfaces, so landmarks guide the
/// correspondence along the surface but cannot pull it off M2.
/// @see docs/numerics.md "Landmarks"
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/lattice/SimplexLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <vector>

namespace vdbmatch {

/// Landmark pairs in Omega units and their weight c_lm.
template <int D> struct LandmarkPairs
{
    std::vector<Vec<D>> source; ///< a_k, inside [0,1]^D
    std::vector<Vec<D>> target; ///< b_k, the same count
    Real weight = 0;            ///< c_lm >= 0
    /// Optional per-pair weights w_k >= 0 (the same count): the term is then
    /// sum_k w_k |phi(a_k) - b_k|^2 and `weight` is not used. Empty: w_k = c_lm / K.
    std::vector<Real> pairWeights;
};

namespace energy {

/// E_lm on one lattice. Immutable once built; queries may run concurrently.
template <int D> class LandmarkTerm
{
public:
    /// @param lattice  must outlive the term; every a_k must lie in one of its cells
    /// @throw openvdb::ValueError if the counts differ, the weight is negative or not finite, a
    ///        coordinate is not finite or an a_k lies outside the lattice
    LandmarkTerm(const SimplexLattice<D>& lattice, const LandmarkPairs<D>& pairs);

    std::size_t size() const { return mTarget.size(); }
    Real weight() const { return mWeight; }

    /// phi(a_k) for the displacement @a u (D x nodeCount).
    Vec<D> mapped(const NodeVectors<D>& u, std::size_t k) const;
    /// E_lm.
    Real value(const NodeVectors<D>& u) const;
    /// E_lm, and its gradient added to @a gradient (D x nodeCount, every node).
    Real addGradient(const NodeVectors<D>& u, NodeVectors<D>& gradient) const;
    /// Mean and largest |phi(a_k) - b_k| (Omega units); 0 without landmarks.
    void residual(const NodeVectors<D>& u, Real& mean, Real& max) const;

private:
    using Location = typename multiscale::PiecewiseLinearInterpolator<D>::Location;
    std::vector<Location> mLocations; ///< the Kuhn simplex of each a_k and its weights
    std::vector<Vec<D>> mSource, mTarget;
    std::vector<Real> mPairWeights; ///< LandmarkPairs::pairWeights
    Real mWeight = 0;
};

extern template class LandmarkTerm<2>;
extern template class LandmarkTerm<3>;

} // namespace energy
} // namespace vdbmatch
