/// @file Descent.h
/// @brief Nonlinear conjugate gradient descent of the matching energy in the weighted H^1 metric
///        with Armijo line search, on one level (paper sec:numerics), and its Report.
///
/// With g_k the L2 gradient of E at u_k (a co-vector, Dirichlet entries dropped) and
/// r_k = G^{-1} g_k its H^1 representative (H1Metric):
/// @f[ p_0 = -r_0,\qquad p_k = -r_k + \beta_k p_{k-1},\qquad u_{k+1} = u_k + t_k p_k, @f]
/// t_k from ArmijoLineSearch (whose trials evaluate the gradient too, so that g_{k+1} comes with
/// the accepted trial: DescentOptions::gradientAtTrials), and the metric inner products
/// - Fletcher-Reeves: beta_k = <g_k, r_k> / <g_{k-1}, r_{k-1}>
/// - Polak-Ribiere+: beta_k = max(0, <g_k - g_{k-1}, r_k> / <g_{k-1}, r_{k-1}>) (default)
/// - steepest descent: beta_k = 0.
/// The direction is reset to -r_k (a "restart") when <g_k, p_k> >= 0, every restartInterval
/// iterations if set, and once after a failed line search before giving up.
///
/// With DescentMethod::LBFGS the direction is instead p_k = -H_k g_k, H_k the limited-memory
/// BFGS inverse Hessian built from the last m pairs s_i = u_{i+1} - u_i (vectors),
/// y_i = g_{i+1} - g_i (co-vectors) over the initial inverse gamma_k G^{-1}, gamma_k =
/// <y, s> / <y, G^{-1} y> from the newest pair (Nocedal & Wright, Numerical Optimization,
/// alg. 7.4, with the metric G as the preconditioner). Since G^{-1} y_i = r_{i+1} - r_i, the
/// two-loop recursion needs no metric solve beyond r_k: the cost per iteration is that of NCG
/// plus O(m) vector operations and 3m stored vectors. The first trial step is 1 (capped so that
/// no node moves by more than maxTrialDisplacementCells h); pairs with <y, s> <= 0 (possible
/// under an Armijo-only search) are skipped, and the memory is cleared when -H g is not a
/// descent direction.
///
/// Stopping rules (defaults in DescentOptions), checked before each iteration in this order:
/// 1. gradient: ||g_k||_{G^{-1}} = sqrt(<g_k, r_k>) <= max(gradientTolerance,
///    relativeGradientTolerance * ||g_0||_{G^{-1}})                      -> Converged
/// 2. interrupter->wasInterrupted() (also queried after an evaluation that returned +inf, to
///    tell cancellation from inversion)                                  -> Interrupted
/// 3. k = maxIterations                                                  -> MaxIterations
/// 4. the line search fails along -r_k (after one restart)               -> LineSearchFailed
/// and after each accepted step:
/// 5. energy stagnation: E_{k-w} - E_k <= energyTolerance * |E_k - C|, w = energyWindow, C the
///    energy's constant part (Energy::constantOffset: 0 for the symmetric energy)
///                                                                       -> Converged
/// 6. settled: E_{k-w} - E_k <= settleTolerance * (E_0 - E_k), E_0 the energy at the start of
///    the run: the last w iterations gained less than a fraction of what the run has gained so
///    far                                                                -> Converged
/// 7. surface settled (with a SurfaceProbe): sum_{j=k-w+1..k} mean_x |phi_j(x) - phi_{j-1}(x)|
///    <= surfaceTolerance over the probe's points x on M1: the map on the source surface
///    stopped moving (a path length, so that a back-and-forth motion does not pass)
///                                                                       -> Converged
/// Test 6 is invariant under adding a constant to E or scaling it; test 5 subtracts the one
/// constant the energies have (c_vol sigma^theta W_vol(1)|Omega| of the directional energy,
/// 63-87% of it at levels 6-7 on the starfish pair), so with either test the symmetric and the
/// directional energy stop at equal convergence.
/// The defaults (relative gradient 1e-4, energy 1e-5 over 5 iterations, 500 iterations) were
/// chosen on circle -> ellipse (2D, levels 4..8) and sphere -> ellipsoid (3D, levels 3..5):
/// there the stagnation test ends every level, after 25-320 iterations, with the matching
/// residual |d2(phi(x))| on M1 already below 1e-2 h (tests/solver/TestDescent.cc).
/// Non-convergence and cancellation are outcomes in the Report, not exceptions; u always holds
/// the last accepted iterate (finite energy, det D phi > 0 on every simplex).
///
/// Progress goes to an IterationObserver; the library never prints.
/// @see paper sec:numerics
#pragma once

#include <vdbmatch/Types.h>
#include <vdbmatch/energy/Energy.h>
#include <vdbmatch/solver/ArmijoLineSearch.h>
#include <vdbmatch/solver/H1Metric.h>
#include <vdbmatch/solver/SurfaceProbe.h>

#include <openvdb/util/NullInterrupter.h>

#include <cstddef>
#include <functional>
#include <string>

namespace vdbmatch {
namespace solver {

/// How a descent (or a level of it) ended.
enum class Status {
    Converged,        ///< a convergence test passed (see Report::convergedBy)
    MaxIterations,    ///< the iteration limit was reached
    LineSearchFailed, ///< no acceptable step even along the steepest descent direction
    Interrupted       ///< the interrupter fired
};
const char* toString(Status status);

/// Which test declared convergence.
enum class ConvergenceTest { None, GradientNorm, EnergyDecrease, Settled, SurfaceSettled };
const char* toString(ConvergenceTest test);

/// Result of a descent at one level, modelled on openvdb::math::pcg::State.
struct Report
{
    Status status = Status::MaxIterations;
    ConvergenceTest convergedBy = ConvergenceTest::None;
    int level = 0;                       ///< lattice level
    int iterations = 0;                  ///< accepted steps
    std::size_t energyEvaluations = 0;   ///< value-only evaluations (line-search trials)
    std::size_t gradientEvaluations = 0; ///< value-and-gradient evaluations
    std::size_t metricIterations = 0;    ///< CG iterations in H1Metric::applyInverse (0: direct)
    int restarts = 0;                    ///< directions reset to steepest descent
    Real initialEnergy = INF;            ///< E at the initial guess
    Real energy = INF;                   ///< E at the result
    EnergyTerms terms;                   ///< terms at the result
    Real initialGradNorm = 0;            ///< ||g||_{G^{-1}} at the initial guess
    Real gradNorm = 0;                   ///< ||g||_{G^{-1}} at the result
    Real lastStep = 0;                   ///< last accepted line-search step t
    Real minJacobian = 0;                ///< min det D phi over the simplices, at the result
    Real elapsedSeconds = 0;             ///< wall time of the descent

    bool isConverged() const { return status == Status::Converged; }
};

/// Progress of one iteration (iteration 0: the initial guess, step 0).
struct IterationInfo
{
    int level = 0;
    int iteration = 0;
    Real energy = INF;
    EnergyTerms terms;
    Real gradNorm = 0;        ///< ||g||_{G^{-1}}
    Real step = 0;            ///< accepted line-search step t
    Real maxDisplacement = 0; ///< max_i |t p_i|, Omega units
    /// Path length of phi on the SurfaceProbe's points over the last w iterations,
    /// sum_j mean_x |phi_j(x) - phi_{j-1}(x)|, Omega units; negative when there is no probe or
    /// fewer than w iterations were done.
    Real surfaceMotion = -1;
    std::size_t energyEvaluations = 0; ///< so far at this level (value and value-and-gradient)
    bool restarted = false;            ///< this iteration moved along -r (steepest descent)
    Real elapsedSeconds = 0;           ///< since the start of the level
};

/// Called after every iteration, on the calling thread.
/// Signature: void(const IterationInfo& info).
using IterationObserver = std::function<void(const IterationInfo&)>;

enum class ConjugateGradientUpdate { SteepestDescent, FletcherReeves, PolakRibierePlus };

/// The descent method: the paper's nonlinear conjugate gradients, or limited-memory BFGS in the
/// same metric (see the file comment).
enum class DescentMethod { NonlinearCG, LBFGS };
const char* toString(DescentMethod method);
/// "ncg" or "lbfgs"; throws openvdb::ValueError otherwise.
DescentMethod parseDescentMethod(const std::string& name);

struct DescentOptions
{
    /// Iteration limit per level.
    int maxIterations = 500;
    /// Converged when ||g||_{G^{-1}} <= relativeGradientTolerance * ||g_0||_{G^{-1}}.
    Real relativeGradientTolerance = 1e-4;
    /// Converged when ||g||_{G^{-1}} <= gradientTolerance (absolute; 0 disables).
    Real gradientTolerance = 0;
    /// Converged when E_{k-w} - E_k <= energyTolerance * |E_k|, w = energyWindow (0 disables).
    Real energyTolerance = 1e-5;
    /// Converged when E_{k-w} - E_k <= settleTolerance * (E_0 - E_k) (0 disables).
    Real settleTolerance = 0;
    /// Converged when phi on the SurfaceProbe's points moved by less than this (path length of
    /// the mean distance, Omega units) over the last energyWindow iterations (0 or no probe:
    /// disabled).
    Real surfaceTolerance = 0;
    /// Window w of the energy and surface tests (0 disables them).
    int energyWindow = 5;
    DescentMethod method = DescentMethod::NonlinearCG;
    ConjugateGradientUpdate update = ConjugateGradientUpdate::PolakRibierePlus;
    /// L-BFGS: number of stored pairs (s, y).
    int lbfgsMemory = 5;
    /// Reset to steepest descent every restartInterval iterations (0: only when needed).
    int restartInterval = 0;
    /// First trial step of a level (and after a restart following a failed search): the node
    /// moving most moves by initialDisplacement * h.
    Real initialDisplacement = 0.5;
    /// L-BFGS: cap of the first trial step, in cells of side h of the moving node.
    Real maxTrialDisplacementCells = 4;
    /// NCG: first trial step of an iteration from the previous one's first-order change,
    /// t_k = t_{k-1} <g_{k-1}, p_{k-1}> / <g_k, p_k> (Nocedal & Wright, Numerical Optimization,
    /// eq. 3.60), capped at lineSearch.grow * t_{k-1}; false: always grow * t_{k-1}.
    bool initialStepFromSlope = false;
    ArmijoOptions lineSearch;
    /// Every line-search trial evaluates value and gradient (Energy::valueAndGradient), so that
    /// the accepted trial's gradient, which the next direction needs, is not evaluated a second
    /// time; false: trials evaluate the value alone and the gradient follows at the accepted
    /// point. The iterates are the same either way (the Armijo test sees the same energy; see
    /// docs/performance.md); true costs less whenever most searches accept within two trials
    /// (1.5 trials per iteration on the benchmark pairs, a value-only evaluation about half a
    /// value-and-gradient one).
    bool gradientAtTrials = true;

    /// Throws openvdb::ValueError naming the first invalid field.
    void validate() const;
};

template <int D> class Descent
{
public:
    /// @param energy, metric  on the same lattice; must outlive the Descent
    /// @throw openvdb::ValueError if the options are invalid or the metric is on another lattice
    Descent(const Energy<D>& energy, const H1Metric<D>& metric, const DescentOptions& opts = {});

    const DescentOptions& options() const { return mOpts; }

    /// Points of M1 whose motion the surface test (DescentOptions::surfaceTolerance) and
    /// IterationInfo::surfaceMotion watch; null: none. Must outlive run().
    void setSurfaceProbe(const SurfaceProbe<D>* probe) { mProbe = probe; }

    /// Minimises E from the initial guess @a u (D x nodeCount, Omega units; projected first:
    /// Dirichlet columns set to 0, hanging columns interpolated, H1Metric::project), leaving the
    /// result in @a u. The unknowns are the free nodes; u stays continuous (P u form).
    /// @param observer     progress callback, may be empty
    /// @param threaded     forwarded to the energy and the metric
    /// @param interrupter  checked once per iteration and forwarded to the energy
    /// @throw openvdb::ValueError if u has the wrong size or E(u) = +inf (an inverted simplex
    ///        in the initial guess), or from Energy (fields sampled outside their coverage).
    Report run(NodeVectors<D>& u, const IterationObserver& observer = {}, bool threaded = true,
               openvdb::util::NullInterrupter* interrupter = nullptr) const;

private:
    const Energy<D>* mEnergy;
    const H1Metric<D>* mMetric;
    DescentOptions mOpts;
    const SurfaceProbe<D>* mProbe = nullptr;
};

extern template class Descent<2>;
extern template class Descent<3>;

} // namespace solver
} // namespace vdbmatch
