#pragma once
// Newton's method with backtracking Armijo line search for
//   min_x E(x),  E = Σ_k w_k E_k,
// over the unknown DOFs (prescribed DOFs are removed from the system and keep
// the values they have in the initial x).
//
// Hessian policy (HessianProjection): element Hessians projected to PSD by
// eigenvalue clamping (Always), or — the default — the exact Hessian first and
// the projected one only if the exact one does not factorise or gives no
// descent direction (Adaptive). Clamping changes the Hessian of compressed
// membranes and tets enough to make Newton converge linearly (the full cloth
// scene stalls at a residual of 1e-3 within 100 iterations with Always); the
// inertia term usually keeps the exact global Hessian positive definite, so
// Adaptive keeps quadratic convergence and skips the eigendecompositions. If
// the projected matrix still fails, μI is added (μ growing ×10) and retried.
#include <string>

#include "energy/energy.hpp"
#include "energy/hessian_assembler.hpp"
#include "solver/sparse_cholesky.hpp"

namespace lb {

struct NewtonOptions {
    int max_iterations = 100;
    /// Converged when ||∇E_free||₂ ≤ gradient_tolerance · force_scale.
    double gradient_tolerance = 1e-8;
    /// Converged when ||Δx||_∞ ≤ step_tolerance · length_scale (a tiny step).
    double step_tolerance = 1e-9;
    /// Force scale (N) and length scale (m) of the two tests above; set by the caller
    /// from the problem (see PhysicsModel::force_scale): the force that moves a mean
    /// vertex by the bounding-box diagonal in one step, and that diagonal.
    double force_scale = 1.0;
    double length_scale = 1.0;
    double armijo_c = 1e-4;
    int max_line_search = 40;
    /// First μ tried on failure, relative to the mean |diagonal| of the Hessian.
    double initial_regularization = 1e-8;
    int max_regularizations = 12;
    enum class Projection { Adaptive, Always, Never };
    Projection projection = Projection::Adaptive;
};

enum class NewtonTermination { Converged, SmallStep, MaxIterations, LineSearchFailed, FactorizationFailed, NonFinite };

std::string to_string(NewtonTermination t);

struct NewtonSummary {
    int iterations = 0;
    /// Final ||∇E_free||₂ / force_scale.
    double residual = 0.0;
    int line_search_halvings = 0;
    int regularizations = 0;
    /// Iterations that needed the PSD-projected Hessian.
    int projected_iterations = 0;
    double seconds = 0.0;
    NewtonTermination termination = NewtonTermination::MaxIterations;
    std::string message;
    bool converged() const
    {
        return termination == NewtonTermination::Converged || termination == NewtonTermination::SmallStep;
    }
    /// One line for logs: "converged in 4 it, residual 3e-10, 0 halvings, 1.2 ms".
    std::string brief() const;
};

class NewtonSolver {
public:
    /// @param dof_to_unknown  3N map, −1 for prescribed DOFs (see HessianAssembler)
    /// @param energies        the terms (the sparsity pattern is built from them once)
    NewtonSolver(const VectorXi& dof_to_unknown, const EnergySum& energies, NewtonOptions options);

    /// Minimise `energies` over the unknowns starting from x (3N, prescribed DOFs
    /// already set); x is overwritten by the result. Never throws on non-convergence:
    /// the summary says what happened.
    NewtonSummary minimize(const EnergySum& energies, VectorXd& x);

    const NewtonOptions& options() const { return m_options; }
    NewtonOptions& options() { return m_options; }
    const HessianAssembler& assembler() const { return m_assembler; }

private:
    /// Factorise the assembled matrix (adding μI if `regularize` and needed) and solve
    /// for a descent direction dx = −H⁻¹g; false if none was found.
    bool solve_direction(const VectorXd& g, bool regularize, VectorXd& dx, NewtonSummary& summary);

    NewtonOptions m_options;
    HessianAssembler m_assembler;
    SparseCholesky m_cholesky;
    std::vector<Index> m_diagonal;  // value index of each diagonal entry
};

} // namespace lb
