#include "solver/newton.hpp"

#include <cmath>
#include <cstdio>

#include "core/timer.hpp"

namespace lb {

std::string to_string(NewtonTermination t)
{
    switch (t) {
    case NewtonTermination::Converged: return "converged";
    case NewtonTermination::SmallStep: return "small step";
    case NewtonTermination::MaxIterations: return "iteration cap reached";
    case NewtonTermination::LineSearchFailed: return "line search failed";
    case NewtonTermination::FactorizationFailed: return "factorisation failed";
    case NewtonTermination::NonFinite: return "non-finite energy or gradient";
    }
    return "unknown";
}

std::string NewtonSummary::brief() const
{
    char buf[256];
    std::snprintf(buf, sizeof buf, "%s in %d it, residual %.3g, %d halvings, %d regularisations, %.2f ms",
                  to_string(termination).c_str(), iterations, residual, line_search_halvings,
                  regularizations, seconds * 1e3);
    return message.empty() ? buf : std::string(buf) + " (" + message + ")";
}

NewtonSolver::NewtonSolver(const VectorXi& dof_to_unknown, const EnergySum& energies,
                           NewtonOptions options)
    : m_options(options), m_assembler(dof_to_unknown, energies)
{
    const SparseMatrixd& A = m_assembler.matrix();
    m_diagonal.resize(size_t(A.cols()));
    for (Index j = 0; j < A.cols(); ++j) {
        // Lower triangle, sorted: the diagonal is the first entry of each column.
        m_diagonal[size_t(j)] = A.outerIndexPtr()[j];
    }
    m_cholesky.analyze(A);
}

bool NewtonSolver::solve_direction(const VectorXd& g, bool regularize, VectorXd& dx, NewtonSummary& summary)
{
    SparseMatrixd& A = m_assembler.mutable_matrix();
    double mean_diag = 0.0;
    for (Index i : m_diagonal) mean_diag += std::abs(A.valuePtr()[i]);
    mean_diag = std::max(mean_diag / double(std::max<size_t>(m_diagonal.size(), 1)), 1e-300);
    double mu = 0.0;
    const int attempts = regularize ? m_options.max_regularizations : 0;
    for (int attempt = 0; attempt <= attempts; ++attempt) {
        if (attempt > 0) {
            const double next_mu = mu == 0.0 ? m_options.initial_regularization * mean_diag : mu * 10.0;
            for (Index i : m_diagonal) A.valuePtr()[i] += next_mu - mu;
            mu = next_mu;
            ++summary.regularizations;
        }
        const FactorStatus status = m_cholesky.factorize(A);
        if (status == FactorStatus::Fatal) {
            summary.message = m_cholesky.message();
            return false;
        }
        if (status == FactorStatus::Success) {
            dx = -m_cholesky.solve(g);
            if (dx.allFinite() && g.dot(dx) < 0.0) return true;
        }
    }
    return false;
}

NewtonSummary NewtonSolver::minimize(const EnergySum& energies, VectorXd& x)
{
    Timer timer;
    NewtonSummary summary;
    const NewtonOptions& opt = m_options;
    const double gtol = opt.gradient_tolerance * opt.force_scale;

    double energy = energies.value(x);
    VectorXd g = m_assembler.restrict(energies.gradient(x));
    for (summary.iterations = 0; summary.iterations < opt.max_iterations; ++summary.iterations) {
        const double gnorm = g.norm();
        summary.residual = gnorm / opt.force_scale;
        if (!std::isfinite(energy) || !std::isfinite(gnorm)) {
            summary.termination = NewtonTermination::NonFinite;
            break;
        }
        if (gnorm <= gtol) {
            summary.termination = NewtonTermination::Converged;
            break;
        }

        // Newton direction: exact Hessian first (Adaptive), then projected, then
        // regularised with μI until it factorises and gives a descent direction.
        VectorXd dx;
        bool have_direction = false;
        // Every iteration tries the exact Hessian first: staying on the projected one
        // after a failure (to save a factorisation) made the full cloth scene stall at
        // the iteration cap (frame 677, residual 1.6e-5) — projection costs quadratic
        // convergence.
        const bool try_exact = opt.projection != NewtonOptions::Projection::Always;
        const bool allow_projected = opt.projection != NewtonOptions::Projection::Never;
        if (try_exact) {
            m_assembler.assemble(energies, x, false);
            have_direction = solve_direction(g, /*regularize=*/!allow_projected, dx, summary);
        }
        if (!have_direction && allow_projected && summary.message.empty()) {
            m_assembler.assemble(energies, x, true);
            ++summary.projected_iterations;
            have_direction = solve_direction(g, /*regularize=*/true, dx, summary);
        }
        if (!have_direction) {
            summary.termination = NewtonTermination::FactorizationFailed;
            if (summary.message.empty()) summary.message = "no descent direction after regularisation";
            break;
        }

        // Backtracking Armijo line search on the full energy.
        const double slope = g.dot(dx);
        double alpha = 1.0;
        VectorXd x_trial = x;
        double trial_energy = energy;
        bool accepted = false;
        for (int ls = 0; ls < opt.max_line_search; ++ls) {
            x_trial = x;
            m_assembler.add_prolonged(alpha * dx, x_trial);
            trial_energy = energies.value(x_trial);
            if (std::isfinite(trial_energy) && trial_energy <= energy + opt.armijo_c * alpha * slope) {
                accepted = true;
                break;
            }
            alpha *= 0.5;
            ++summary.line_search_halvings;
        }
        const double step = alpha * dx.lpNorm<Eigen::Infinity>();
        if (!accepted) {
            // At the precision floor the energy cannot decrease measurably: a tiny
            // full step means we are converged to round-off.
            if (dx.lpNorm<Eigen::Infinity>() <= opt.step_tolerance * opt.length_scale * 1e3) {
                summary.termination = NewtonTermination::SmallStep;
            } else {
                summary.termination = NewtonTermination::LineSearchFailed;
                summary.message = "no sufficient decrease after " + std::to_string(opt.max_line_search) + " halvings";
            }
            break;
        }
        x.swap(x_trial);
        energy = trial_energy;
        g = m_assembler.restrict(energies.gradient(x));
        if (step <= opt.step_tolerance * opt.length_scale) {
            summary.residual = g.norm() / opt.force_scale;
            summary.termination = NewtonTermination::SmallStep;
            ++summary.iterations;
            break;
        }
    }
    if (summary.iterations >= opt.max_iterations) {
        summary.residual = g.norm() / opt.force_scale;
        summary.termination = g.norm() <= gtol ? NewtonTermination::Converged : NewtonTermination::MaxIterations;
    }
    summary.seconds = timer.seconds();
    return summary;
}

} // namespace lb
