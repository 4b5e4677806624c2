#pragma once
// Newton's method with backtracking Armijo line search for min_x f(x), f an
// Objective with a dense or a sparse Hessian (minimize_newton), and NewtonSolver,
// which applies it to E(x) = Σ_k w_k E_k over the unknown DOFs of a mesh
// (prescribed DOFs are removed from the system and keep the values they have in
// the initial x).
//
// Hessian policy (Projection): the PSD-projected Hessian (element Hessians
// projected by eigenvalue clamping) on every iteration (Always), or — the
// default — the exact Hessian first and the projected one only if the exact one
// does not factorise or gives no descent direction (Adaptive). Clamping changes the
// Hessian of compressed membranes and tets enough to make Newton converge linearly
// (the full cloth scene stalls at a residual of 1e-3 within 100 iterations with
// Always); the inertia term usually keeps the exact global Hessian positive
// definite, so Adaptive keeps quadratic convergence and skips the
// eigendecompositions. If the projected matrix still fails, μI is added (μ growing
// ×regularization_growth) and retried. Never: the exact Hessian, regularised.
#include <memory>
#include <vector>

#include <Eigen/Cholesky>

#include "energy/energy.hpp"
#include "energy/hessian_assembler.hpp"
#include "solver/objective.hpp"
#include "solver/solve_summary.hpp"
#include "solver/sparse_cholesky.hpp"

namespace lb {

struct NewtonOptions {
    int max_iterations = 100;
    /// Converged when ||∇f||₂ ≤ gradient_tolerance · force_scale.
    double gradient_tolerance = 1e-8;
    /// Converged when the step moves nothing by more than step_tolerance · length_scale
    /// (Objective::step_length of the accepted step).
    double step_tolerance = 1e-9;
    /// Force scale (N) and length scale (m) of the two tests above; set by the caller
    /// from the problem (see PhysicsModel::force_scale): the force that moves a mean
    /// vertex by the bounding-box diagonal in one step, and that diagonal.
    double force_scale = 1.0;
    double length_scale = 1.0;
    /// Armijo constant c (dimensionless): accept α when f(x + α dx) ≤ f(x) + c α ∇fᵀdx.
    double armijo_c = 1e-4;
    /// Backtracking steps before the line search gives up.
    int max_line_search = 40;
    /// α is multiplied by this at each backtracking step (dimensionless, in (0, 1)).
    double backtracking_factor = 0.5;
    /// When the line search fails, a full step with step_length ≤ small_step_factor ·
    /// step_tolerance · length_scale is at the round-off floor (f cannot decrease
    /// measurably): reported SmallStep, not LineSearchFailed. Dimensionless.
    double small_step_factor = 1e3;
    /// First μ tried on failure, relative to the mean |diagonal| of the Hessian.
    double initial_regularization = 1e-8;
    /// μ is multiplied by this after each failed regularised factorisation.
    double regularization_growth = 10.0;
    int max_regularizations = 12;
    enum class Projection { Adaptive, Always, Never };
    Projection projection = Projection::Adaptive;
    /// Sparse Hessians: before factorising the exact Hessian, try at most this many
    /// conjugate-gradient iterations on it, preconditioned by the last Cholesky factor that
    /// succeeded (of an earlier iteration, or of an earlier call with the same workspace).
    /// The direction is accepted when ||H d + ∇f|| ≤ η ||∇f||, η = min(cg_forcing_max,
    /// ||∇f|| / ||∇f₀||) (∇f₀: the call's first gradient), so that the convergence stays
    /// superlinear; a stale factor, negative curvature or no convergence falls back to a
    /// new factorisation. Only a factor of the exact, unshifted Hessian is used (after a
    /// projected or shifted one, the next direction is factorised): CG does not see that
    /// an exact Hessian is indefinite as a factorisation does. For the solids and rods
    /// (tests/sim/test_small_scenes.cpp); the small cloth amplifies any tolerance-sized
    /// difference about 2.7-fold per frame. Scene key [solver] lagged_factor_cg.
    /// 0 (default): every direction is a direct solve.
    int lagged_factor_cg = 0;
    double cg_forcing_max = 0.1;
};

/// Storage minimize_newton reuses between calls: the CHOLMOD symbolic analysis of
/// a sparse Hessian's pattern (redone only when the pattern changes) and the
/// vectors and dense factorisation of one solve. One workspace per objective pattern
/// keeps the analysis; not to be shared between threads.
class NewtonWorkspace {
public:
    NewtonWorkspace();
    ~NewtonWorkspace();
    NewtonWorkspace(NewtonWorkspace&&) noexcept;
    NewtonWorkspace& operator=(NewtonWorkspace&&) noexcept;

    /// Symbolic analysis of a lower-triangular pattern (done lazily by
    /// minimize_newton otherwise); throws NumericalError if CHOLMOD rejects it.
    void analyze(const SparseMatrixd& lower);

private:
    friend SolveSummary minimize_newton(Objective&, VectorXd&, const NewtonOptions&, NewtonWorkspace*);
    /// Re-analyse `lower` unless its pattern is the one analysed last.
    void ensure_analyzed(const SparseMatrixd& lower);
    // The steps of one Newton iteration (newton.cpp): m_dx for the exact or projected
    // Hessian, the Adaptive policy over both, and the Armijo search along m_dx.
    bool newton_direction(Objective& f, const VectorXd& x, bool project_psd, bool regularize,
                          const NewtonOptions& opt, SolveSummary& summary);
    bool find_direction(Objective& f, const VectorXd& x, const NewtonOptions& opt, SolveSummary& summary);
    bool armijo_search(Objective& f, const VectorXd& x, double energy, double slope, const NewtonOptions& opt,
                       SolveSummary& summary, double& alpha, double& trial_energy);

    /// d ≈ A⁻¹g by CG preconditioned by m_cholesky's factor (NewtonOptions::lagged_factor_cg);
    /// false on negative curvature or without convergence in `max_iterations`.
    bool lagged_factor_cg(const SparseMatrixd& A, const VectorXd& g, double eta, int max_iterations, VectorXd& d,
                          SolveSummary& summary);

    std::unique_ptr<SparseCholesky> m_cholesky;  // created on first sparse use
    bool m_factor_current = false;  // m_cholesky holds a successful factor of the analysed pattern
    bool m_factor_exact = false;    // ... of an exact Hessian, unshifted (it was positive definite)
    double m_g0_norm = 0.0;         // ||∇f|| at the start of the current minimize_newton call
    VectorXd m_cg_r, m_cg_z, m_cg_p, m_cg_q;
    std::vector<Index> m_outer, m_inner;         // the analysed pattern
    std::vector<Index> m_diagonal;               // value index of each diagonal entry
    MatrixXd m_dense;
    Eigen::LDLT<MatrixXd> m_ldlt;
    VectorXd m_g, m_dx, m_step, m_x_trial;
};

/// Minimise f from x (size f.dimension()); x is overwritten by the last accepted
/// iterate. Each iteration solves H dx = −∇f with the Hessian policy above (sparse:
/// CHOLMOD LLᵀ; dense: LDLᵀ with a positive-D check), then backtracks from α = 1
/// until the Armijo condition holds. Never throws on non-convergence (including a
/// non-finite f or an objective without a Hessian): the summary says what happened.
/// @param workspace  reused between calls (keeps the CHOLMOD analysis); nullptr: a
///                   temporary one
SolveSummary minimize_newton(Objective& f, VectorXd& x, const NewtonOptions& options,
                             NewtonWorkspace* workspace = nullptr);

/// Newton on E(x) = Σ_k w_k E_k over the unknown DOFs of a mesh: owns the Hessian
/// assembler (pattern and scatter maps) and the CHOLMOD analysis, both built once.
struct FreeDofBuffers;

class NewtonSolver {
public:
    /// @param dof_to_unknown  3N map, −1 for prescribed DOFs (see HessianAssembler)
    /// @param energies        the terms (the sparsity pattern is built from them once)
    NewtonSolver(const VectorXi& dof_to_unknown, const EnergySum& energies, NewtonOptions options);
    ~NewtonSolver();
    NewtonSolver(NewtonSolver&&) noexcept;
    NewtonSolver& operator=(NewtonSolver&&) noexcept;

    /// Minimise `energies` (the terms given at construction) over the unknowns starting
    /// from x (3N, prescribed DOFs already set); x is overwritten by the result. Never
    /// throws on non-convergence: the summary says what happened.
    SolveSummary minimize(const EnergySum& energies, VectorXd& x);

    const NewtonOptions& options() const { return m_options; }
    NewtonOptions& options() { return m_options; }
    const HessianAssembler& assembler() const { return m_assembler; }

private:
    NewtonOptions m_options;
    HessianAssembler m_assembler;
    NewtonWorkspace m_workspace;
    std::unique_ptr<FreeDofBuffers> m_free;  // the objective's 3N vectors, kept between calls
    VectorXd m_y;                            // the unknowns
};

} // namespace lb
