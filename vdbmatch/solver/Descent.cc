/// @file Descent.cc
#include "Descent.h"

#include <openvdb/Exceptions.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace vdbmatch {
namespace solver {

const char*
toString(Status status)
{
    switch (status) {
    case Status::Converged:
        return "converged";
    case Status::MaxIterations:
        return "max iterations";
    case Status::LineSearchFailed:
        return "line search failed";
    case Status::Interrupted:
        return "interrupted";
    }
    return "unknown";
}

const char*
toString(ConvergenceTest test)
{
    switch (test) {
    case ConvergenceTest::None:
        return "none";
    case ConvergenceTest::GradientNorm:
        return "gradient norm";
    case ConvergenceTest::EnergyDecrease:
        return "energy decrease";
    case ConvergenceTest::Settled:
        return "settled";
    case ConvergenceTest::SurfaceSettled:
        return "surface settled";
    }
    return "unknown";
}

const char*
toString(DescentMethod method)
{
    return method == DescentMethod::LBFGS ? "lbfgs" : "ncg";
}

DescentMethod
parseDescentMethod(const std::string& name)
{
    if (name == "ncg") return DescentMethod::NonlinearCG;
    if (name == "lbfgs") return DescentMethod::LBFGS;
    OPENVDB_THROW(openvdb::ValueError,
                  "parseDescentMethod: expected 'ncg' or 'lbfgs', got '" << name << "'");
}

void
DescentOptions::validate() const
{
    auto fail = [](const char* what) {
        OPENVDB_THROW(openvdb::ValueError, "DescentOptions: " << what);
    };
    if (maxIterations < 0) fail("maxIterations must be >= 0");
    if (!(relativeGradientTolerance >= 0) || !std::isfinite(relativeGradientTolerance))
        fail("relativeGradientTolerance must be finite and >= 0");
    if (!(gradientTolerance >= 0) || !std::isfinite(gradientTolerance))
        fail("gradientTolerance must be finite and >= 0");
    if (!(energyTolerance >= 0) || !std::isfinite(energyTolerance))
        fail("energyTolerance must be finite and >= 0");
    if (!(settleTolerance >= 0) || !std::isfinite(settleTolerance))
        fail("settleTolerance must be finite and >= 0");
    if (!(surfaceTolerance >= 0) || !std::isfinite(surfaceTolerance))
        fail("surfaceTolerance must be finite and >= 0");
    if (energyWindow < 0) fail("energyWindow must be >= 0");
    if (restartInterval < 0) fail("restartInterval must be >= 0");
    if (lbfgsMemory < 1) fail("lbfgsMemory must be >= 1");
    if (!(maxTrialDisplacementCells > 0) || !std::isfinite(maxTrialDisplacementCells))
        fail("maxTrialDisplacementCells must be finite and > 0");
    if (!(initialDisplacement > 0) || !std::isfinite(initialDisplacement))
        fail("initialDisplacement must be finite and > 0");
    lineSearch.validate();
}

template <int D>
Descent<D>::Descent(const Energy<D>& energy, const H1Metric<D>& metric, const DescentOptions& opts)
    : mEnergy(&energy), mMetric(&metric), mOpts(opts)
{
    mOpts.validate();
    if (&metric.lattice() != &energy.lattice())
        OPENVDB_THROW(openvdb::ValueError,
                      "Descent: the metric and the energy must be built on the same lattice");
}

template <int D>
Report
Descent<D>::run(NodeVectors<D>& u, const IterationObserver& observer, bool threaded,
                openvdb::util::NullInterrupter* interrupter) const
{
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    auto elapsed = [&] { return std::chrono::duration<Real>(Clock::now() - start).count(); };

    const Energy<D>& energy = *mEnergy;
    const H1Metric<D>& metric = *mMetric;
    const SimplexLattice<D>& lattice = energy.lattice();
    const Real h = lattice.h();
    if (std::size_t(u.cols()) != lattice.nodeCount() || u.rows() != D)
        OPENVDB_THROW(openvdb::ValueError, "Descent::run: expected "
                                               << D << " x " << lattice.nodeCount()
                                               << " displacements, got " << u.rows() << " x "
                                               << u.cols());
    // The initial guess in the constrained space: u = 0 on the Dirichlet nodes, hanging nodes
    // interpolated (continuous P1 field).
    metric.project(u);

    Report report;
    report.level = lattice.level();
    auto interrupted = [&] { return interrupter && interrupter->wasInterrupted(); };
    auto finish = [&](Status status) {
        report.status = status;
        report.minJacobian = energy.minJacobianDeterminant(u, threaded);
        report.elapsedSeconds = elapsed();
        return report;
    };

    // Gradient at u: g (co-vector over every node, Dirichlet entries zeroed; hanging entries
    // kept: applyInverse moves them to their masters), r = G^{-1} g expanded (r = P x), <g, r>.
    // Every direction p is a combination of such r, so u + t p stays in the constrained space.
    NodeVectors<D> g, r, gNew, rNew, p, uNew;
    // The metric's CG starts from 0: starting from the previous representative (the initial
    // guess of H1Metric::applyInverse) was measured to save nothing, the NCG gradients turn too
    // much between iterations (16.5 CG iterations per solve at level 8 of the starfish pair,
    // against 14.0 from 0).
    auto representative = [&](NodeVectors<D>& gx, NodeVectors<D>& rx) {
        metric.zeroDirichlet(gx);
        report.metricIterations += std::size_t(metric.applyInverse(gx, rx, threaded).iterations);
    };
    auto gradientAt = [&](const NodeVectors<D>& x, NodeVectors<D>& gx, NodeVectors<D>& rx,
                          EnergyTerms& terms) -> Real {
        const Real E = energy.valueAndGradient(x, gx, &terms, threaded, interrupter);
        ++report.gradientEvaluations;
        if (!std::isfinite(E)) return E;
        representative(gx, rx);
        return E;
    };

    EnergyTerms terms;
    Real E = gradientAt(u, g, r, terms);
    if (!std::isfinite(E)) {
        if (interrupted()) return finish(Status::Interrupted);
        OPENVDB_THROW(openvdb::ValueError, "Descent::run: the energy of the initial guess is +inf ("
                                               << terms.invertedSimplices
                                               << " simplices with det D phi <= 0)");
    }
    Real gg = metric.pairing(g, r);
    report.initialEnergy = report.energy = E;
    report.terms = terms;
    report.initialGradNorm = report.gradNorm = std::sqrt(std::max(gg, Real(0)));
    const Real gradLimit =
        std::max(mOpts.gradientTolerance, mOpts.relativeGradientTolerance * report.initialGradNorm);

    // The path length of phi on the probe's points over the last w iterations, for the surface
    // test: sum_j mean_x |phi_j(x) - phi_{j-1}(x)|. A path length, unlike the net motion over
    // the window, does not dip when the surface moves back and forth.
    const std::size_t window = std::size_t(mOpts.energyWindow);
    const bool probing = mProbe && !mProbe->empty() && window > 0;
    NodeVectors<D> surface, surfaceNew;
    std::vector<Real> surfaceSteps;
    if (probing) mProbe->displacements(u, surface);
    Real surfaceMotion = -1;

    auto notify = [&](int iteration, Real step, Real maxDisplacement, bool restarted) {
        if (!observer) return;
        IterationInfo info;
        info.level = report.level;
        info.iteration = iteration;
        info.energy = report.energy;
        info.terms = report.terms;
        info.gradNorm = report.gradNorm;
        info.step = step;
        info.maxDisplacement = maxDisplacement;
        info.surfaceMotion = surfaceMotion;
        info.energyEvaluations = report.energyEvaluations + report.gradientEvaluations;
        info.restarted = restarted;
        info.elapsedSeconds = elapsed();
        observer(info);
    };
    notify(0, 0, 0, true);

    ArmijoLineSearch<D> lineSearch(mOpts.lineSearch);
    auto steepest = [&] {
        p = -r;
        const Real pMax = p.size() ? p.cwiseAbs().maxCoeff() : 0.0;
        if (pMax > 0) lineSearch.setInitialStep(mOpts.initialDisplacement * h / pMax);
        return -gg;
    };
    Real slope = steepest();
    bool restarted = true;

    // L-BFGS memory, oldest first, and the two-loop recursion p = -H g (see Descent.h).
    struct Pair
    {
        NodeVectors<D> s, y, Gy;
        Real rho;
    };
    const bool lbfgs = mOpts.method == DescentMethod::LBFGS;
    std::vector<Pair> memory;
    std::vector<Real> alpha;
    NodeVectors<D> q;
    auto lbfgsDirection = [&] {
        if (memory.empty()) {
            p = -r;
            return;
        }
        alpha.assign(memory.size(), 0);
        q = g;
        p = r; // becomes G^{-1} q = r - sum alpha_i G^{-1} y_i
        for (std::size_t k = memory.size(); k-- > 0;) {
            const Pair& m = memory[k];
            alpha[k] = m.rho * metric.pairing(q, m.s);
            q -= alpha[k] * m.y;
            p -= alpha[k] * m.Gy;
        }
        const Pair& newest = memory.back();
        const Real yGy = metric.pairing(newest.y, newest.Gy);
        const Real gamma = yGy > 0 ? 1 / (newest.rho * yGy) : 1;
        p *= gamma;
        for (std::size_t k = 0; k < memory.size(); ++k) {
            const Pair& m = memory[k];
            const Real b = m.rho * metric.pairing(m.y, p);
            p += (alpha[k] - b) * m.s;
        }
        p = -p;
    };
    std::vector<Real> history{E};
    // The relative stagnation test compares with E minus its constant part (zero for the
    // symmetric energy), so that it means the same for both energies.
    const Real offset = energy.constantOffset();

    while (true) {
        if (!(report.gradNorm > gradLimit)) {
            report.convergedBy = ConvergenceTest::GradientNorm;
            return finish(Status::Converged);
        }
        if (interrupted()) return finish(Status::Interrupted);
        if (report.iterations >= mOpts.maxIterations) return finish(Status::MaxIterations);

        const bool trialGradients = mOpts.gradientAtTrials;
        const LineSearchResult ls = lineSearch.search(
            energy, u, E, slope, p, uNew, threaded, interrupter, trialGradients ? &gNew : nullptr);
        (trialGradients ? report.gradientEvaluations : report.energyEvaluations) +=
            std::size_t(ls.evaluations);
        if (ls.status == LineSearchStatus::Interrupted) return finish(Status::Interrupted);
        if (!ls.isAccepted()) {
            if (restarted) return finish(Status::LineSearchFailed);
            ++report.restarts;
            memory.clear();
            slope = steepest();
            restarted = true;
            continue;
        }

        const Real maxDisplacement = ls.step * p.cwiseAbs().maxCoeff();
        u.swap(uNew);
        Real Enew = ls.energy;
        if (trialGradients) {
            // gNew is the gradient at the accepted trial (ArmijoLineSearch::search), the same
            // valueAndGradient call gradientAt() would make.
            terms = ls.terms;
            representative(gNew, rNew);
        } else {
            Enew = gradientAt(u, gNew, rNew, terms);
        }
        ++report.iterations;
        report.lastStep = ls.step;
        if (!std::isfinite(Enew)) {
            // Only cancellation can make the energy of an accepted step infinite.
            report.energy = ls.energy;
            report.terms = ls.terms;
            return finish(Status::Interrupted);
        }
        const Real ggNew = metric.pairing(gNew, rNew);
        if (lbfgs) {
            // The new pair: s = t p, y = gNew - g, G^{-1} y = rNew - r.
            Pair pair{ls.step * p, gNew - g, rNew - r, 0};
            const Real ys = metric.pairing(pair.y, pair.s);
            if (ys > 0 && std::isfinite(ys)) {
                pair.rho = 1 / ys;
                if (int(memory.size()) == mOpts.lbfgsMemory) memory.erase(memory.begin());
                memory.push_back(std::move(pair));
            }
        }
        Real beta = 0;
        switch (mOpts.update) {
        case ConjugateGradientUpdate::SteepestDescent:
            beta = 0;
            break;
        case ConjugateGradientUpdate::FletcherReeves:
            beta = gg > 0 ? ggNew / gg : 0.0;
            break;
        case ConjugateGradientUpdate::PolakRibierePlus:
            beta = gg > 0 ? std::max(Real(0), (ggNew - metric.pairing(g, rNew)) / gg) : 0.0;
            break;
        }
        if (mOpts.restartInterval > 0 && report.iterations % mOpts.restartInterval == 0) beta = 0;

        const bool movedSteepest = restarted;
        E = Enew;
        g.swap(gNew);
        r.swap(rNew);
        gg = ggNew;
        report.energy = E;
        report.terms = terms;
        report.gradNorm = std::sqrt(std::max(gg, Real(0)));

        // Next direction; restart when it is not a descent direction.
        if (lbfgs) {
            lbfgsDirection();
            slope = metric.pairing(g, p);
            restarted = memory.empty();
        } else {
            const Real previousSlope = slope;
            p = beta * p - r;
            slope = metric.pairing(g, p);
            restarted = beta == 0;
            if (mOpts.initialStepFromSlope && slope < 0 && previousSlope < 0) {
                lineSearch.setInitialStep(std::min(mOpts.lineSearch.grow, previousSlope / slope) *
                                          ls.step);
            }
        }
        if (!(slope < 0)) {
            ++report.restarts;
            memory.clear();
            p = -r;
            slope = -gg;
            restarted = true;
        }
        if (lbfgs && !memory.empty()) {
            const Real pMax = p.size() ? p.cwiseAbs().maxCoeff() : 0.0;
            const Real cap = pMax > 0 ? mOpts.maxTrialDisplacementCells * h / pMax : 1.0;
            lineSearch.setInitialStep(std::min(Real(1), cap));
        }
        if (probing) {
            mProbe->displacements(u, surfaceNew);
            surfaceSteps.push_back(SurfaceProbe<D>::meanDistance(surfaceNew, surface));
            surface.swap(surfaceNew);
            if (surfaceSteps.size() >= window) {
                surfaceMotion = 0;
                for (std::size_t j = surfaceSteps.size() - window; j < surfaceSteps.size(); ++j)
                    surfaceMotion += surfaceSteps[j];
            }
        }
        notify(report.iterations, ls.step, maxDisplacement, movedSteepest);

        history.push_back(E);
        const std::size_t w = std::size_t(mOpts.energyWindow);
        if (w > 0 && history.size() > w) {
            const Real recent = history[history.size() - 1 - w] - E;
            if (recent <= mOpts.energyTolerance * std::abs(E - offset)) {
                report.convergedBy = ConvergenceTest::EnergyDecrease;
                return finish(Status::Converged);
            }
            if (mOpts.settleTolerance > 0 && recent <= mOpts.settleTolerance * (history[0] - E)) {
                report.convergedBy = ConvergenceTest::Settled;
                return finish(Status::Converged);
            }
        }
        if (mOpts.surfaceTolerance > 0 && surfaceMotion >= 0 &&
            surfaceMotion <= mOpts.surfaceTolerance) {
            report.convergedBy = ConvergenceTest::SurfaceSettled;
            return finish(Status::Converged);
        }
    }
}

template class Descent<2>;
template class Descent<3>;

} // namespace solver
} // namespace vdbmatch
