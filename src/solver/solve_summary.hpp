#pragma once
// What one minimisation did, the same struct for every optimiser (Newton, L-BFGS):
// non-convergence is reported here as data, never thrown.
#include <string>

namespace lb {

enum class SolveTermination {
    /// ||∇f|| ≤ gradient_tolerance · force_scale.
    Converged,
    /// The step fell below step_tolerance · length_scale (Newton: also a full step too
    /// small to decrease f measurably; L-BFGS: NLopt's relative xtol).
    SmallStep,
    /// L-BFGS: the relative decrease of f fell below NLopt's ftol.
    SmallDecrease,
    /// Newton: max_iterations steps without meeting a test above.
    MaxIterations,
    /// L-BFGS: max_evaluations evaluations without meeting a test above.
    MaxEvaluations,
    /// No sufficient decrease along a descent direction.
    LineSearchFailed,
    /// Newton: no regularised Hessian factorised into a descent direction.
    FactorizationFailed,
    /// f or ∇f is NaN or ±inf at the current point.
    NonFinite,
    /// L-BFGS: NLopt stopped because round-off limited progress.
    RoundoffLimited,
    /// L-BFGS: NLopt stopped on an internal test of its own before ||∇f|| reached the
    /// tolerance (see message).
    Stalled,
    /// Anything else (invalid arguments, out of memory, no Hessian for Newton); see message.
    Failed,
};

std::string to_string(SolveTermination t);

struct SolveSummary {
    SolveTermination termination = SolveTermination::MaxIterations;
    /// Newton steps taken; for L-BFGS the evaluations that lowered f (NLopt does not
    /// expose its iteration count).
    int iterations = 0;
    /// Evaluations of f (Newton: one per trial point of the line search, plus the start).
    int evaluations = 0;
    /// Final ||∇f||₂ / force_scale.
    double residual = 0.0;
    int line_search_halvings = 0;
    /// Newton: diagonal shifts μI tried.
    int regularizations = 0;
    /// Newton: iterations that needed the PSD-projected Hessian.
    int projected_iterations = 0;
    /// Newton, sparse: numeric Cholesky factorisations, and conjugate-gradient iterations
    /// on a lagged factor (NewtonOptions::lagged_factor_cg).
    int factorizations = 0;
    int cg_iterations = 0;
    double seconds = 0.0;
    std::string message;

    /// Converged, or stopped on a step / decrease too small to matter.
    bool converged() const
    {
        return termination == SolveTermination::Converged || termination == SolveTermination::SmallStep ||
               termination == SolveTermination::SmallDecrease;
    }
    /// One line for logs: "converged in 4 it, residual 3e-10, 0 halvings, 0 regularisations, 1.20 ms".
    std::string brief() const;
};

} // namespace lb
