/// @file ArmijoLineSearch.h
/// @brief Backtracking line search with the Armijo sufficient-decrease condition on
///        t -> E(u + t p), for the descent of paper sec:numerics.
///
/// A trial step t is accepted when
/// @f[ E(u + t p) \le E(u) + c_1\, t\, \langle g, p\rangle, @f]
/// with g the L2 gradient (co-vector) at u and <g, p> < 0. Otherwise t shrinks and is tried
/// again: to the minimiser of the quadratic through E(u), <g, p> and E(u + t p), kept in
/// [0.1 t, shrink t] (`interpolate`, default; it halved the rejected trials on the tests'
/// problems), or to shrink * t. A trial whose energy is +inf (a simplex with det D phi <= 0) is
/// simply rejected, as is, without an energy evaluation, a trial that moves a node out of the
/// closed unit box: phi = Id on the boundary of Omega and det D phi > 0 make phi map Omega onto
/// itself, so such a step would invert a simplex anyway (on lattices that cover Omega), and the
/// check keeps the shape samplers inside their coverage. The search never produces NaN.
///
/// The first trial of a search is `grow` times the last accepted step (setInitialStep() sets
/// it explicitly, e.g. from a displacement scale at the start of a level). The search fails when
/// the largest nodal displacement of the trial step, t max_i |p_i|, falls below
/// `minDisplacement`, or after `maxEvaluations` energy evaluations.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/lattice/SimplexLattice.h>

#include <openvdb/util/NullInterrupter.h>

#include <functional>

namespace vdbmatch {
namespace solver {

/// Sufficient-decrease constant c1 (Nocedal & Wright, Numerical Optimization, sec. 3.1).
constexpr Real DEFAULT_ARMIJO_C1 = 1e-4;

struct ArmijoOptions
{
    Real c1 = DEFAULT_ARMIJO_C1; ///< sufficient-decrease constant, in (0, 1)
    Real shrink = 0.5;           ///< backtracking factor, in (0, 1)
    Real grow = 2.0;             ///< next first trial = grow * accepted step, >= 1
    /// Failure when the trial step moves no node by more than this (Omega units): far below
    /// any meaningful displacement, near the rounding of node positions in the unit box.
    Real minDisplacement = 1e-13;
    int maxEvaluations = 60; ///< energy evaluations per search
    /// Backtrack to the minimiser of the quadratic interpolating E(u), <g, p> and the rejected
    /// finite E(u + t p), safeguarded to [0.1 t, shrink t]; false: always t *= shrink.
    bool interpolate = true;

    /// Throws openvdb::ValueError naming the first invalid field.
    void validate() const;
};

enum class LineSearchStatus {
    Accepted,
    NotDescentDirection, ///< <g, p> >= 0 (or not finite): nothing evaluated
    StepUnderflow,       ///< no acceptable step above minDisplacement
    TooManyEvaluations,  ///< maxEvaluations reached
    Interrupted          ///< the interrupter fired during an evaluation
};

const char* toString(LineSearchStatus status);

struct LineSearchResult
{
    LineSearchStatus status = LineSearchStatus::StepUnderflow;
    Real step = 0;            ///< accepted t (0 unless Accepted)
    Real energy = INF;        ///< E(u + t p) if Accepted, else E(u)
    EnergyTerms terms;        ///< terms of the accepted energy (if Accepted)
    int evaluations = 0;      ///< energy evaluations made
    int rejectedInfinite = 0; ///< trials rejected for +inf energy or a node outside the unit box

    bool isAccepted() const { return status == LineSearchStatus::Accepted; }
};

/// Energy of a trial step: returns E(u + t p) (+inf to reject) and fills @a terms; sets
/// @a evaluated to false if the trial was rejected without evaluating the energy.
/// Signature: Real(Real t, EnergyTerms& terms, bool& evaluated).
using TrialEnergy = std::function<Real(Real, EnergyTerms&, bool&)>;

/// The backtracking core on a scalar function (for tests and other energies).
/// @param trial      E(u + t p), see TrialEnergy
/// @param E0         E(u), finite
/// @param slope      <g, p>, must be < 0
/// @param t0         first trial step, > 0
/// @param pMax       max_i |p_i| (Omega units), for the underflow test
/// @param interrupter  queried after a trial returned +inf (to tell cancellation from
///                     inversion); may be null
LineSearchResult armijoBacktrack(const TrialEnergy& trial, Real E0, Real slope, Real t0, Real pMax,
                                 const ArmijoOptions& opts,
                                 openvdb::util::NullInterrupter* interrupter = nullptr);

/// Armijo line search on an Energy, remembering the accepted step between calls.
/// Not thread-safe (holds the step); one per descent.
template <int D> class ArmijoLineSearch
{
public:
    /// @throw openvdb::ValueError if the options are invalid
    explicit ArmijoLineSearch(const ArmijoOptions& opts = {});

    const ArmijoOptions& options() const { return mOpts; }
    /// First trial step of the next search.
    Real initialStep() const { return mInitialStep; }
    void setInitialStep(Real t) { mInitialStep = t; }

    /// Searches along @a p from @a u. On acceptance @a uNew = u + t p and the next first trial
    /// becomes grow * t; otherwise @a uNew is unspecified and the first trial is unchanged.
    /// @param E0     energy.value(u), finite
    /// @param slope  <g, p> with g the L2 gradient at u (Dirichlet entries excluded)
    /// @param p      direction, D x nodeCount, 0 on Dirichlet nodes
    /// @param threaded, interrupter  forwarded to Energy::value
    /// @param gradient  null: each trial evaluates the energy alone (Energy::value). Otherwise
    ///        each trial evaluates value and gradient (Energy::valueAndGradient) into it, so that
    ///        on acceptance it holds the L2 gradient at @a uNew, the point where a descent needs
    ///        it next; the accepted energy and terms are then those of valueAndGradient.
    LineSearchResult search(const Energy<D>& energy, const NodeVectors<D>& u, Real E0, Real slope,
                            const NodeVectors<D>& p, NodeVectors<D>& uNew, bool threaded = true,
                            openvdb::util::NullInterrupter* interrupter = nullptr,
                            NodeVectors<D>* gradient = nullptr);

private:
    ArmijoOptions mOpts;
    Real mInitialStep = 1;
};

extern template class ArmijoLineSearch<2>;
extern template class ArmijoLineSearch<3>;

} // namespace solver
} // namespace vdbmatch
