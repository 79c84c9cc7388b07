/// @file ArmijoLineSearch.cc
#include "ArmijoLineSearch.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <cmath>

namespace vdbmatch {
namespace solver {

namespace {
/// Smallest backtracking factor allowed to the quadratic interpolation (Nocedal & Wright,
/// sec. 3.5, safeguard of the interpolating backtracking).
constexpr Real MIN_INTERPOLATED_SHRINK = 0.1;
} // namespace

void
ArmijoOptions::validate() const
{
    if (!(c1 > 0 && c1 < 1))
        OPENVDB_THROW(openvdb::ValueError, "ArmijoOptions: c1 must be in (0, 1), got " << c1);
    if (!(shrink > 0 && shrink < 1))
        OPENVDB_THROW(openvdb::ValueError,
                      "ArmijoOptions: shrink must be in (0, 1), got " << shrink);
    if (!(grow >= 1 && std::isfinite(grow)))
        OPENVDB_THROW(openvdb::ValueError,
                      "ArmijoOptions: grow must be finite and >= 1, got " << grow);
    if (!(minDisplacement > 0 && std::isfinite(minDisplacement)))
        OPENVDB_THROW(openvdb::ValueError, "ArmijoOptions: minDisplacement must be finite and "
                                           "> 0, got "
                                               << minDisplacement);
    if (maxEvaluations < 1)
        OPENVDB_THROW(openvdb::ValueError,
                      "ArmijoOptions: maxEvaluations must be >= 1, got " << maxEvaluations);
}

const char*
toString(LineSearchStatus status)
{
    switch (status) {
    case LineSearchStatus::Accepted:
        return "accepted";
    case LineSearchStatus::NotDescentDirection:
        return "not a descent direction";
    case LineSearchStatus::StepUnderflow:
        return "step underflow";
    case LineSearchStatus::TooManyEvaluations:
        return "too many evaluations";
    case LineSearchStatus::Interrupted:
        return "interrupted";
    }
    return "unknown";
}

LineSearchResult
armijoBacktrack(const TrialEnergy& trial, Real E0, Real slope, Real t0, Real pMax,
                const ArmijoOptions& opts, openvdb::util::NullInterrupter* interrupter)
{
    LineSearchResult result;
    result.energy = E0;
    if (!(slope < 0) || !std::isfinite(slope) || !(pMax > 0) || !std::isfinite(pMax)) {
        result.status = LineSearchStatus::NotDescentDirection;
        return result;
    }
    Real t = t0 > 0 && std::isfinite(t0) ? t0 : 1.0 / pMax;
    while (true) {
        if (!(t * pMax >= opts.minDisplacement)) {
            result.status = LineSearchStatus::StepUnderflow;
            return result;
        }
        if (result.evaluations >= opts.maxEvaluations) {
            result.status = LineSearchStatus::TooManyEvaluations;
            return result;
        }
        EnergyTerms terms;
        bool evaluated = true;
        const Real E = trial(t, terms, evaluated);
        if (evaluated) ++result.evaluations;
        if (!std::isfinite(E)) {
            if (evaluated && interrupter && interrupter->wasInterrupted()) {
                result.status = LineSearchStatus::Interrupted;
                return result;
            }
            ++result.rejectedInfinite;
        } else if (E <= E0 + opts.c1 * t * slope) {
            result.status = LineSearchStatus::Accepted;
            result.step = t;
            result.energy = E;
            result.terms = terms;
            return result;
        } else if (opts.interpolate) {
            // Minimiser of the quadratic through E0, slope and E(t), kept in
            // [MIN_INTERPOLATED_SHRINK t, shrink t].
            const Real curvature = E - E0 - slope * t;
            const Real tq = curvature > 0 ? -slope * t * t / (2 * curvature) : opts.shrink * t;
            t = std::clamp(tq, MIN_INTERPOLATED_SHRINK * t, opts.shrink * t);
            continue;
        }
        t *= opts.shrink;
    }
}

template <int D> ArmijoLineSearch<D>::ArmijoLineSearch(const ArmijoOptions& opts) : mOpts(opts)
{
    mOpts.validate();
}

template <int D>
LineSearchResult
ArmijoLineSearch<D>::search(const Energy<D>& energy, const NodeVectors<D>& u, Real E0, Real slope,
                            const NodeVectors<D>& p, NodeVectors<D>& uNew, bool threaded,
                            openvdb::util::NullInterrupter* interrupter, NodeVectors<D>* gradient)
{
    const auto& L = energy.lattice();
    const Real h = L.h();
    const Real pMax = p.size() ? p.cwiseAbs().maxCoeff() : 0.0;
    auto trial = [&](Real t, EnergyTerms& terms, bool& evaluated) -> Real {
        uNew = u + t * p;
        // Every deformed node in the closed unit box (index coordinates times h are exact).
        for (std::size_t i = 0; i < L.nodeCount(); ++i) {
            const auto& ijk = L.nodeCoord(i);
            for (int a = 0; a < D; ++a) {
                const Real y = ijk[a] * h + uNew(a, Eigen::Index(i));
                if (!(y >= 0 && y <= 1)) {
                    evaluated = false;
                    return INF;
                }
            }
        }
        evaluated = true;
        if (gradient)
            return energy.valueAndGradient(uNew, *gradient, &terms, threaded, interrupter);
        return energy.value(uNew, &terms, threaded, interrupter);
    };
    LineSearchResult result =
        armijoBacktrack(trial, E0, slope, mInitialStep, pMax, mOpts, interrupter);
    if (result.isAccepted()) {
        mInitialStep = mOpts.grow * result.step;
        // uNew (and the gradient, if asked for) hold the last trial, the accepted one.
    }
    return result;
}

template class ArmijoLineSearch<2>;
template class ArmijoLineSearch<3>;

} // namespace solver
} // namespace vdbmatch
