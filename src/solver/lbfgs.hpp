#pragma once
// L-BFGS (NLopt's NLOPT_LD_LBFGS, Lukšan's limited-memory variable metric method)
// for min_x f(x) with f an Objective: gradient only, no Hessian. Meant for many
// small solves (one per simulation step), so the NLopt handle can be kept in an
// LbfgsWorkspace between calls.
//
// Stopping: ||∇f||₂ ≤ gradient_tolerance · force_scale, tested in every evaluation
// (NLopt has no such test; the callback stops it with nlopt_force_stop), and
// optionally NLopt's relative ftol / xtol. NLopt also stops on its own when the
// largest |∂f/∂x_i| falls below 1e-8 (absolute, not configurable): reported Stalled
// if our test has not passed there. A NaN or ±inf f or ∇f stops the solve
// (NonFinite): Lukšan's line search cannot backtrack from one.
#include <memory>

#include "solver/objective.hpp"
#include "solver/solve_summary.hpp"

namespace lb {

struct LbfgsOptions {
    /// Correction pairs kept (the m of L-BFGS; NLopt's "vector storage"); 0: NLopt's
    /// heuristic default (memory-based, at least 10).
    int history_size = 10;
    /// Cap on evaluations of f and ∇f (NLopt counts no iterations); reached: MaxEvaluations.
    int max_evaluations = 1000;
    /// Converged when ||∇f||₂ ≤ gradient_tolerance · force_scale.
    double gradient_tolerance = 1e-8;
    /// Force scale of the test above (N for a potential over positions; see
    /// PhysicsModel::force_scale); 1 for a dimensionless objective.
    double force_scale = 1.0;
    /// NLopt ftol_rel: stop (SmallDecrease) when f changes by ≤ ftol·|f| between
    /// iterations; 0 disables it (NLopt then uses 1e-14 internally).
    double relative_ftol = 0.0;
    /// NLopt xtol_rel: stop (SmallStep) when x changes by ≤ xtol·|x|; 0 disables it
    /// (NLopt then uses 1e-16 internally).
    double relative_xtol = 0.0;
};

/// The NLopt handle (re-created only when the dimension changes) and the buffers of
/// one solve, reused between calls of minimize_lbfgs. Not to be shared between threads.
class LbfgsWorkspace {
public:
    LbfgsWorkspace();
    ~LbfgsWorkspace();
    LbfgsWorkspace(const LbfgsWorkspace&) = delete;
    LbfgsWorkspace& operator=(const LbfgsWorkspace&) = delete;

    struct Impl;

private:
    friend SolveSummary minimize_lbfgs(Objective&, VectorXd&, const LbfgsOptions&, LbfgsWorkspace*);
    std::unique_ptr<Impl> m_impl;
};

/// Minimise f from x (size f.dimension()); x is overwritten by the point where the
/// gradient test passed, or else by the lowest finite f seen (x unchanged if f is
/// not finite there). Never throws on non-convergence: the summary says what
/// happened, with NLopt's result in the message when it is not ours.
/// @param workspace  reused between calls (keeps the NLopt handle); nullptr: a temporary one
SolveSummary minimize_lbfgs(Objective& f, VectorXd& x, const LbfgsOptions& options,
                            LbfgsWorkspace* workspace = nullptr);

} // namespace lb
