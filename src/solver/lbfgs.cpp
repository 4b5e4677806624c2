#include "solver/lbfgs.hpp"

#include <nlopt.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/timer.hpp"

namespace lb {

struct LbfgsWorkspace::Impl {
    nlopt_opt opt = nullptr;
    Index dimension = -1;
    VectorXd x_work;   // the iterate NLopt moves
    VectorXd best_x;   // lowest finite f seen
    VectorXd stop_x;   // where the gradient test passed
    VectorXd stop_g;
    VectorXd scratch;  // gradient of an evaluation NLopt asks without one

    ~Impl()
    {
        if (opt) nlopt_destroy(opt);
    }
};

LbfgsWorkspace::LbfgsWorkspace() : m_impl(std::make_unique<Impl>()) { }
LbfgsWorkspace::~LbfgsWorkspace() = default;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

struct CallbackState {
    Objective* f = nullptr;
    LbfgsWorkspace::Impl* ws = nullptr;
    double gtol = 0.0;
    int max_evaluations = 0;  // ≤ 0: no cap
    int evaluations = 0;
    int improvements = 0;  // evaluations that lowered the best f
    bool converged = false;
    bool non_finite = false;
    bool capped = false;  // max_evaluations reached
    double best_f = std::numeric_limits<double>::infinity();
    double best_gnorm = kNaN;
    double stop_f = 0.0;
    double stop_gnorm = kNaN;
};

/// NLopt's objective: f and ∇f at x, with the gradient test and the bookkeeping of
/// the best point.
double evaluate(unsigned n, const double* x, double* grad, void* data)
{
    CallbackState& s = *static_cast<CallbackState*>(data);
    LbfgsWorkspace::Impl& ws = *s.ws;
    const Index dim = Index(n);
    Eigen::Map<VectorXd> g(grad ? grad : ws.scratch.data(), dim);
    if (s.converged || s.non_finite || s.capped) {
        // NLopt notices a forced stop (and its own evaluation cap) only when its line
        // search ends: answer the remaining trial points without evaluating f.
        if (s.converged) {
            g = ws.stop_g;
            return s.stop_f;
        }
        g.setZero();
        return std::numeric_limits<double>::infinity();
    }
    const Eigen::Map<const VectorXd> xm(x, dim);
    const double fx = s.f->value_and_gradient(xm, g);
    const double gnorm = g.norm();
    ++s.evaluations;
    if (!std::isfinite(fx) || !std::isfinite(gnorm)) {
        s.non_finite = true;
        nlopt_force_stop(ws.opt);
        return fx;
    }
    if (fx < s.best_f) {
        s.best_f = fx;
        s.best_gnorm = gnorm;
        ws.best_x = xm;
        ++s.improvements;
    }
    if (gnorm <= s.gtol) {
        s.converged = true;
        s.stop_f = fx;
        s.stop_gnorm = gnorm;
        ws.stop_x = xm;
        ws.stop_g = g;
        nlopt_force_stop(ws.opt);
    } else if (s.max_evaluations > 0 && s.evaluations >= s.max_evaluations) {
        s.capped = true;
        nlopt_force_stop(ws.opt);
    }
    return fx;
}

/// Our termination for an NLopt result that was not our own forced stop.
SolveTermination from_nlopt(nlopt_result result)
{
    switch (result) {
    case NLOPT_FTOL_REACHED: return SolveTermination::SmallDecrease;
    case NLOPT_XTOL_REACHED: return SolveTermination::SmallStep;
    case NLOPT_MAXEVAL_REACHED: return SolveTermination::MaxEvaluations;
    case NLOPT_ROUNDOFF_LIMITED: return SolveTermination::RoundoffLimited;
    case NLOPT_SUCCESS:
    case NLOPT_STOPVAL_REACHED: return SolveTermination::Stalled;
    default: return SolveTermination::Failed;
    }
}

} // namespace

SolveSummary minimize_lbfgs(Objective& f, VectorXd& x, const LbfgsOptions& options, LbfgsWorkspace* workspace)
{
    Timer timer;
    SolveSummary summary;
    const Index n = f.dimension();
    if (x.size() != n) {
        summary.termination = SolveTermination::Failed;
        summary.message = "x has " + std::to_string(x.size()) + " entries, the objective " + std::to_string(n) +
                          " unknowns";
        return summary;
    }
    std::unique_ptr<LbfgsWorkspace> local;
    if (!workspace) {
        local = std::make_unique<LbfgsWorkspace>();
        workspace = local.get();
    }
    LbfgsWorkspace::Impl& ws = *workspace->m_impl;
    if (n == 0) {  // NLopt rejects an empty problem; there is nothing to minimise
        summary.termination = SolveTermination::Converged;
        summary.seconds = timer.seconds();
        return summary;
    }
    if (!ws.opt || ws.dimension != n) {
        if (ws.opt) nlopt_destroy(ws.opt);
        ws.opt = nlopt_create(NLOPT_LD_LBFGS, unsigned(n));
        ws.dimension = ws.opt ? n : -1;
        if (!ws.opt) {
            summary.termination = SolveTermination::Failed;
            summary.message = "nlopt_create failed (out of memory)";
            return summary;
        }
    }
    nlopt_opt opt = ws.opt;
    CallbackState state;
    state.f = &f;
    state.ws = &ws;
    state.gtol = options.gradient_tolerance * options.force_scale;
    state.max_evaluations = options.max_evaluations;
    ws.scratch.resize(n);
    nlopt_set_min_objective(opt, evaluate, &state);
    nlopt_set_vector_storage(opt, unsigned(std::max(options.history_size, 0)));
    nlopt_set_maxeval(opt, std::max(options.max_evaluations, 0));
    nlopt_set_ftol_rel(opt, options.relative_ftol);
    nlopt_set_xtol_rel(opt, options.relative_xtol);
    nlopt_set_force_stop(opt, 0);

    ws.x_work = x;
    double f_min = 0.0;
    const nlopt_result result = nlopt_optimize(opt, ws.x_work.data(), &f_min);

    summary.evaluations = state.evaluations;
    summary.iterations = std::max(state.improvements - 1, 0);
    const bool have_best = state.improvements > 0;
    if (state.converged) {
        summary.termination = SolveTermination::Converged;
        x = ws.stop_x;
        summary.residual = state.stop_gnorm / options.force_scale;
    } else {
        if (have_best) x = ws.best_x;
        summary.residual = have_best ? state.best_gnorm / options.force_scale : kNaN;
        if (state.non_finite) {
            summary.termination = SolveTermination::NonFinite;
            summary.message = "f or its gradient is not finite at evaluation " + std::to_string(state.evaluations) +
                              (have_best ? "; x is the lowest finite point" : "; x is the start");
        } else {
            summary.termination = state.capped ? SolveTermination::MaxEvaluations : from_nlopt(result);
            if (summary.termination == SolveTermination::Stalled || summary.termination == SolveTermination::Failed) {
                const char* detail = nlopt_get_errmsg(opt);
                summary.message = std::string("NLopt: ") + nlopt_result_to_string(result) +
                                  (detail ? std::string(", ") + detail : std::string()) +
                                  (summary.termination == SolveTermination::Stalled
                                       ? " before ||g|| reached the tolerance"
                                       : "");
            }
        }
    }
    summary.seconds = timer.seconds();
    return summary;
}

} // namespace lb
