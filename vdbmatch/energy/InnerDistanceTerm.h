/// @file InnerDistanceTerm.h
/// @brief Optional inner-distance term, an addition to the paper's energy (eq:Esym and
///        eq:Ecomparison have none): phi should keep F_k, the inner distance from the paired
///        extremity k (geometry/InnerDistance.h), which an articulation keeps and a slide of the
///        skin along a limb changes, where the distances d1, d2 of eq:EsymMatch see no change.
///
/// With F1_k, F2_k the fields of M1 and M2 for the extremity pair k, points p_i of M1 with
/// weights w_i (c_F times the share of M1's area or length around p_i) and k_i the extremity
/// of M1 nearest to p_i inside (the least F1_k(p_i)),
/// @f[ E_F[\phi] = \sum_i w_i\, \psi_\tau\big(F_{2,k_i}(\phi(p_i)) - F_{1,k_i}(p_i)\big), \qquad
///     \psi_\tau(r) = \max(|r| - \tau, 0)^2 @f]
/// so c_F times the mean of psi over M1. Each point keeps its distance to its own extremity's
/// partner: the distance to the nearest extremity of M2, whichever it is, would let a hand's
/// skin slide onto the other hand or the head, where that distance is as small. The tolerance tau
/// ignores what F itself cannot tell: where an extremity is placed, the eikonal solver's error, the
/// stretch of a near-isometric pose. On a level's lattice phi(p_i) = p_i + sum_m lambda_im u(v_im)
/// (the P1 interpolant on the Kuhn simplex containing p_i, as LandmarkTerm.h) and F2 the
/// multilinear interpolant of its lattice, so the gradient at node v_im, 2 w_i psi'/2 (r_i) grad
/// F2_k(phi(p_i)) lambda_im with psi'/2 = sign(r)(|r| - tau)_+, is exact wherever F2's interpolant
/// is differentiable (off the faces of its cells, a set of measure zero).
///
/// Only the direct half, as for landmarks: when phi keeps F on M1 and maps M1 onto M2, its
/// inverse keeps F on M2, and the run from M2 to M1 uses the same fields swapped.
/// @see docs/numerics.md "The inner distance"
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/geometry/InnerDistance.h>
#include <vdbmatch/lattice/SimplexLattice.h>
#include <vdbmatch/multiscale/Prolongation.h>

#include <cstdint>
#include <memory>
#include <vector>

namespace vdbmatch {

/// The points of M1 and the field of M2 of E_F (Omega units).
template <int D> struct InnerDistanceSamples
{
    std::vector<Vec<D>> points;   ///< p_i, inside [0,1]^D
    std::vector<Real> values;     ///< F1_{k_i}(p_i), the same count
    std::vector<Real> weights;    ///< w_i >= 0, the same count (c_F included)
    std::vector<uint32_t> fields; ///< k_i, indices into targets, the same count
    /// F2_k; none empty(). Shared: the terms of every level use the same fields.
    std::vector<std::shared_ptr<const InnerDistanceField<D>>> targets;
    Real tolerance = 0; ///< tau >= 0
};

namespace energy {

/// E_F on one lattice. Immutable once built; queries may run concurrently.
template <int D> class InnerDistanceTerm
{
public:
    /// @param lattice  must outlive the term; every p_i must lie in one of its cells
    /// @throw openvdb::ValueError if the counts differ, a weight or the tolerance is negative or
    ///        not finite, a value or coordinate is not finite, a field index is out of range, a
    ///        field is missing or empty, or a p_i lies outside the lattice
    InnerDistanceTerm(const SimplexLattice<D>& lattice, const InnerDistanceSamples<D>& samples);

    std::size_t size() const { return mPoints.size(); }

    /// E_F.
    Real value(const NodeVectors<D>& u) const { return evaluate(u, nullptr); }
    /// E_F, and its gradient added to @a gradient (D x nodeCount, every node).
    Real addGradient(const NodeVectors<D>& u, NodeVectors<D>& gradient) const
    {
        return evaluate(u, &gradient);
    }
    /// The weighted mean of |F2(phi(p_i)) - F1(p_i)| (Omega units; 0 without points), and the
    /// weighted share of the points where it exceeds the tolerance.
    void residual(const NodeVectors<D>& u, Real& mean, Real& beyondTolerance) const;

private:
    Real evaluate(const NodeVectors<D>& u, NodeVectors<D>* gradient) const;

    using Location = typename multiscale::PiecewiseLinearInterpolator<D>::Location;
    std::vector<Location> mLocations; ///< the Kuhn simplex of each p_i and its weights
    std::vector<Vec<D>> mPoints;
    std::vector<Real> mValues, mWeights;
    std::vector<uint32_t> mFields;
    std::vector<std::shared_ptr<const InnerDistanceField<D>>> mTargets;
    Real mTolerance = 0;
};

extern template class InnerDistanceTerm<2>;
extern template class InnerDistanceTerm<3>;

} // namespace energy
} // namespace vdbmatch
