#include "solver/newton.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/timer.hpp"
#include "solver/free_dof_objective.hpp"

namespace lb {

namespace {

/// Floor of the mean |diagonal| that μ is relative to, so that μ > 0 even for an
/// all-zero diagonal.
constexpr double kTinyDiagonal = 1e-300;

/// dx = −H⁻¹g with H the current matrix, shifted by μI (μ growing from
/// initial_regularization · mean_diag by regularization_growth) while it does not
/// factorise or gives no descent direction, if `regularize`; false if no descent
/// direction was found (with summary.message set if the failure is fatal).
/// `shift(d)` adds d to the diagonal, `factorize()` returns a FactorStatus (and the
/// message of a fatal one), `solve(g, dx)` sets dx = H⁻¹g.
template <class Shift, class Factorize, class Solve>
bool regularized_direction(double mean_diag, bool regularize, const NewtonOptions& opt, const VectorXd& g,
                           VectorXd& dx, SolveSummary& summary, Shift shift, Factorize factorize, Solve solve)
{
    mean_diag = std::max(mean_diag, kTinyDiagonal);
    double mu = 0.0;
    const int attempts = regularize ? opt.max_regularizations : 0;
    for (int attempt = 0; attempt <= attempts; ++attempt) {
        if (attempt > 0) {
            const double next_mu = mu == 0.0 ? opt.initial_regularization * mean_diag : mu * opt.regularization_growth;
            shift(next_mu - mu);
            mu = next_mu;
            ++summary.regularizations;
        }
        std::string message;
        const FactorStatus status = factorize(message);
        if (status == FactorStatus::Fatal) {
            summary.message = message;
            return false;
        }
        if (status == FactorStatus::Success) {
            solve(g, dx);
            dx = -dx;
            if (dx.allFinite() && g.dot(dx) < 0.0) return true;
        }
    }
    return false;
}

} // namespace

NewtonWorkspace::NewtonWorkspace() = default;
NewtonWorkspace::~NewtonWorkspace() = default;
NewtonWorkspace::NewtonWorkspace(NewtonWorkspace&&) noexcept = default;
NewtonWorkspace& NewtonWorkspace::operator=(NewtonWorkspace&&) noexcept = default;

void NewtonWorkspace::analyze(const SparseMatrixd& lower)
{
    if (!lower.isCompressed() || lower.rows() != lower.cols())
        throw std::invalid_argument("Newton: the sparse Hessian must be square and compressed");
    const auto* outer = lower.outerIndexPtr();
    const auto* inner = lower.innerIndexPtr();
    m_diagonal.resize(size_t(lower.cols()));
    for (Index j = 0; j < lower.cols(); ++j) {
        // Lower triangle, sorted: the diagonal is the first entry of each column.
        if (outer[j] == outer[j + 1] || inner[outer[j]] != j)
            throw std::invalid_argument("Newton: the sparse Hessian must store the diagonal entry first in column " +
                                        std::to_string(j) + " (lower triangle, sorted)");
        m_diagonal[size_t(j)] = outer[j];
    }
    if (!m_cholesky) m_cholesky = std::make_unique<SparseCholesky>();
    m_factor_current = false;
    m_cholesky->analyze(lower);
    m_outer.assign(outer, outer + lower.cols() + 1);
    m_inner.assign(inner, inner + lower.nonZeros());
}

void NewtonWorkspace::ensure_analyzed(const SparseMatrixd& lower)
{
    const bool same = m_cholesky && lower.isCompressed() && size_t(lower.cols()) + 1 == m_outer.size() &&
                      size_t(lower.nonZeros()) == m_inner.size() &&
                      std::equal(m_outer.begin(), m_outer.end(), lower.outerIndexPtr()) &&
                      std::equal(m_inner.begin(), m_inner.end(), lower.innerIndexPtr());
    if (!same) analyze(lower);
}

/// dx = −H⁻¹g for the Hessian (exact or projected) at x, shifted by μI if `regularize`
/// and needed (see regularized_direction); false if no descent direction was found.
bool NewtonWorkspace::newton_direction(Objective& f, const VectorXd& x, bool project_psd, bool regularize,
                                       const NewtonOptions& opt, SolveSummary& summary)
{
    NewtonWorkspace& ws = *this;
    VectorXd& dx = ws.m_dx;
    if (f.hessian_kind() == HessianKind::Sparse) {
        SparseMatrixd& A = f.sparse_hessian(x, project_psd);
        ws.ensure_analyzed(A);
        if (!project_psd && opt.lagged_factor_cg > 0 && ws.m_factor_current && ws.m_factor_exact) {
            const double gnorm = ws.m_g.norm();
            const double eta = std::min(opt.cg_forcing_max, ws.m_g0_norm > 0.0 ? gnorm / ws.m_g0_norm : 1.0);
            if (ws.lagged_factor_cg(A, ws.m_g, eta, opt.lagged_factor_cg, dx, summary)) {
                dx = -dx;
                if (dx.allFinite() && ws.m_g.dot(dx) < 0.0) return true;
            }
        }
        double mean_diag = 0.0;
        for (Index i : ws.m_diagonal) mean_diag += std::abs(A.valuePtr()[i]);
        mean_diag /= double(std::max<size_t>(ws.m_diagonal.size(), 1));
        const int regularizations_before = summary.regularizations;
        return regularized_direction(
            mean_diag, regularize, opt, ws.m_g, dx, summary,
            [&](double d) {
                for (Index i : ws.m_diagonal) A.valuePtr()[i] += d;
            },
            [&](std::string& message) {
                const FactorStatus status = ws.m_cholesky->factorize(A);
                ++summary.factorizations;
                ws.m_factor_current = status == FactorStatus::Success;
                ws.m_factor_exact = !project_psd && summary.regularizations == regularizations_before;
                message = ws.m_cholesky->message();
                return status;
            },
            [&](const VectorXd& b, VectorXd& out) { ws.m_cholesky->solve(b, out); });
    }
    MatrixXd& H = ws.m_dense;
    f.dense_hessian(x, project_psd, H);
    const double mean_diag = H.size() ? H.diagonal().cwiseAbs().mean() : 0.0;
    return regularized_direction(
        mean_diag, regularize, opt, ws.m_g, dx, summary, [&](double d) { H.diagonal().array() += d; },
        [&](std::string& message) {
            if (!H.allFinite()) {
                message = "non-finite entry in the Hessian";
                return FactorStatus::Fatal;
            }
            ws.m_ldlt.compute(H);
            const bool ok = ws.m_ldlt.info() == Eigen::Success && (ws.m_ldlt.vectorD().array() > 0.0).all();
            return ok ? FactorStatus::Success : FactorStatus::NotPositiveDefinite;
        },
        [&](const VectorXd& b, VectorXd& out) { out = ws.m_ldlt.solve(b); });
}

bool NewtonWorkspace::lagged_factor_cg(const SparseMatrixd& A, const VectorXd& g, double eta, int max_iterations,
                                       VectorXd& d, SolveSummary& summary)
{
    const double target = eta * g.norm();
    VectorXd &r = m_cg_r, &z = m_cg_z, &p = m_cg_p, &q = m_cg_q;
    d.setZero(g.size());
    r = g;
    m_cholesky->solve(r, z);
    p = z;
    double rz = r.dot(z);
    for (int k = 0; k < max_iterations; ++k) {
        q.noalias() = A.selfadjointView<Eigen::Lower>() * p;
        const double curvature = p.dot(q);
        ++summary.cg_iterations;
        if (!(curvature > 0.0) || !(rz > 0.0)) return false;  // indefinite, or a breakdown
        const double a = rz / curvature;
        d.noalias() += a * p;
        r.noalias() -= a * q;
        if (r.norm() <= target) return true;
        m_cholesky->solve(r, z);
        const double rz_next = r.dot(z);
        p = z + (rz_next / rz) * p;
        rz = rz_next;
    }
    return false;
}

/// Newton direction: exact Hessian first (Adaptive), then projected, then regularised
/// with μI until it factorises and gives a descent direction. Every iteration tries
/// the exact Hessian first: staying on the projected one after a failure (to save a
/// factorisation) made the full cloth scene stall at the iteration cap (frame 677,
/// residual 1.6e-5) — projection costs quadratic convergence.
bool NewtonWorkspace::find_direction(Objective& f, const VectorXd& x, const NewtonOptions& opt, SolveSummary& summary)
{
    const bool try_exact = opt.projection != NewtonOptions::Projection::Always;
    const bool allow_projected = opt.projection != NewtonOptions::Projection::Never;
    bool have_direction = false;
    if (try_exact) have_direction = newton_direction(f, x, false, /*regularize=*/!allow_projected, opt, summary);
    if (!have_direction && allow_projected && summary.message.empty()) {
        ++summary.projected_iterations;
        have_direction = newton_direction(f, x, true, /*regularize=*/true, opt, summary);
    }
    return have_direction;
}

/// Backtracking Armijo line search along ws.m_dx from x (energy, slope gᵀdx); on
/// success ws.m_x_trial holds x + α dx. The step α dx is formed before it is added so
/// that x + α dx rounds the same way for every objective.
bool NewtonWorkspace::armijo_search(Objective& f, const VectorXd& x, double energy, double slope,
                                    const NewtonOptions& opt, SolveSummary& summary, double& alpha, double& trial_energy)
{
    NewtonWorkspace& ws = *this;
    alpha = 1.0;
    trial_energy = energy;
    for (int ls = 0; ls < opt.max_line_search; ++ls) {
        ws.m_step.noalias() = alpha * ws.m_dx;
        ws.m_x_trial.noalias() = x + ws.m_step;
        trial_energy = f.value(ws.m_x_trial);
        ++summary.evaluations;
        if (std::isfinite(trial_energy) && trial_energy <= energy + opt.armijo_c * alpha * slope) return true;
        alpha *= opt.backtracking_factor;
        ++summary.line_search_halvings;
    }
    return false;
}

namespace {

/// Failed for an objective Newton cannot run on; "" if it can.
std::string unusable(const Objective& f, const VectorXd& x)
{
    if (f.hessian_kind() == HessianKind::None)
        return "Newton needs a Hessian and this objective has none (use minimize_lbfgs)";
    if (x.size() != f.dimension())
        return "x has " + std::to_string(x.size()) + " entries, the objective " + std::to_string(f.dimension()) +
               " unknowns";
    return "";
}

} // namespace

SolveSummary minimize_newton(Objective& f, VectorXd& x, const NewtonOptions& opt, NewtonWorkspace* workspace)
{
    Timer timer;
    SolveSummary summary;
    summary.message = unusable(f, x);
    if (!summary.message.empty()) {
        summary.termination = SolveTermination::Failed;
        return summary;
    }
    NewtonWorkspace local;
    NewtonWorkspace& ws = workspace ? *workspace : local;
    const double gtol = opt.gradient_tolerance * opt.force_scale;
    const double step_tol = opt.step_tolerance * opt.length_scale;

    VectorXd& g = ws.m_g;
    g.resize(x.size());
    double energy = f.value(x);
    ++summary.evaluations;
    f.gradient(x, g);
    ws.m_g0_norm = g.norm();
    bool stopped = true;
    auto stop = [&](SolveTermination t) { summary.termination = t; };
    for (summary.iterations = 0;; ++summary.iterations) {
        if (summary.iterations >= opt.max_iterations) {
            stopped = false;
            break;
        }
        const double gnorm = g.norm();
        summary.residual = gnorm / opt.force_scale;
        if (!std::isfinite(energy) || !std::isfinite(gnorm)) {
            stop(SolveTermination::NonFinite);
            break;
        }
        if (gnorm <= gtol) {
            stop(SolveTermination::Converged);
            break;
        }
        if (!ws.find_direction(f, x, opt, summary)) {
            stop(SolveTermination::FactorizationFailed);
            if (summary.message.empty()) summary.message = "no descent direction after regularisation";
            break;
        }
        double alpha = 1.0, trial_energy = energy;
        const bool accepted = ws.armijo_search(f, x, energy, g.dot(ws.m_dx), opt, summary, alpha, trial_energy);
        const double full_step = f.step_length(ws.m_dx);
        if (!accepted) {
            // At the precision floor the energy cannot decrease measurably: a tiny
            // full step means we are converged to round-off.
            if (full_step <= opt.small_step_factor * step_tol) {
                stop(SolveTermination::SmallStep);
            } else {
                stop(SolveTermination::LineSearchFailed);
                summary.message = "no sufficient decrease after " + std::to_string(opt.max_line_search) + " halvings";
            }
            break;
        }
        x.swap(ws.m_x_trial);
        energy = trial_energy;
        f.gradient(x, g);
        if (alpha * full_step <= step_tol) {
            summary.residual = g.norm() / opt.force_scale;
            stop(SolveTermination::SmallStep);
            ++summary.iterations;
            break;
        }
    }
    if (!stopped) {
        summary.residual = g.norm() / opt.force_scale;
        summary.termination = g.norm() <= gtol ? SolveTermination::Converged : SolveTermination::MaxIterations;
    }
    summary.seconds = timer.seconds();
    return summary;
}

NewtonSolver::NewtonSolver(const VectorXi& dof_to_unknown, const EnergySum& energies, NewtonOptions options)
    : m_options(options), m_assembler(dof_to_unknown, energies), m_free(std::make_unique<FreeDofBuffers>())
{
    m_workspace.analyze(m_assembler.matrix());
}

NewtonSolver::~NewtonSolver() = default;
NewtonSolver::NewtonSolver(NewtonSolver&&) noexcept = default;
NewtonSolver& NewtonSolver::operator=(NewtonSolver&&) noexcept = default;

SolveSummary NewtonSolver::minimize(const EnergySum& energies, VectorXd& x)
{
    // The objective works in m_free (3N state and gradient) and Newton on m_y: from the
    // second call on, with the sizes reached, a solve allocates nothing of its own.
    FreeDofObjective objective(m_assembler, energies, x, m_free.get());
    objective.unknowns(x, m_y);
    const SolveSummary summary = minimize_newton(objective, m_y, m_options, &m_workspace);
    x = objective.full_state(m_y);
    return summary;
}

} // namespace lb
