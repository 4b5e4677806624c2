#include "baselines/fulton_cubature/fulton_integrator.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <tuple>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "latent/latent_potential.hpp"

namespace lb {

namespace {
constexpr int kMaxNodes = 8;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
} // namespace

/// Φ as the Objective L-BFGS minimises (a view of the integrator's current step).
class FultonIntegrator::StepObjective final : public Objective {
public:
    explicit StepObjective(FultonIntegrator& owner) : m_owner(owner) { }
    /// z = z₀ + P y.
    VectorXd latent(const Eigen::Ref<const VectorXd>& y) const { return m_owner.m_z_start + m_owner.m_P * y; }
    Index dimension() const override { return m_owner.m_split.latent_dim(); }
    double value(const Eigen::Ref<const VectorXd>& y) override { return m_owner.evaluate(latent(y), nullptr); }
    void gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g) override { value_and_gradient(y, g); }
    double value_and_gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g) override
    {
        VectorXd grad_z;
        const double f = m_owner.evaluate(latent(y), &grad_z);
        g.noalias() = m_owner.m_P.transpose() * grad_z;
        return f;
    }
    double step_length(const Eigen::Ref<const VectorXd>& dy) override
    {
        return (m_owner.m_P * dy).lpNorm<Eigen::Infinity>();
    }

private:
    FultonIntegrator& m_owner;
};

FultonIntegrator::FultonIntegrator(std::string name, std::shared_ptr<Autoencoder> autoencoder,
                                   const PhysicsModel& model, std::optional<Cubature> cubature, FultonOptions options)
    : m_name(std::move(name)),
      m_autoencoder(std::move(autoencoder)),
      m_model(model),
      m_cubature(std::move(cubature)),
      m_options(options),
      m_split(*m_autoencoder, model),
      m_penalty_weight(applied_penalty_weight(model, options.penalty_weight))
{
    m_lbfgs.gradient_tolerance = options.gradient_tolerance;
    m_lbfgs.force_scale = std::sqrt(model.force_scale() * model.length_scale());
    m_lbfgs.max_evaluations = options.max_evaluations;
    m_lbfgs.history_size = options.history_size;
    const Index N = model.num_vertices();
    m_x_buffer = model.rest_state();
    if (m_cubature) {
        std::vector<int> slot(size_t(N), -1);
        auto slot_of = [&](int v) {
            if (slot[size_t(v)] < 0) {
                slot[size_t(v)] = int(m_vertices.size());
                m_vertices.push_back(v);
            }
            return slot[size_t(v)];
        };
        for (const CubatureElement& c : m_cubature->elements) {
            const Energy& energy = *model.elastic_terms()[size_t(c.term)];
            if (energy.nodes_per_element() > kMaxNodes)
                throw Error("fulton: elements of " + energy.name() + " have too many vertices");
            const int* nodes = energy.element_nodes(c.element);
            for (int k = 0; k < energy.nodes_per_element(); ++k) m_element_slots.push_back(slot_of(nodes[k]));
        }
        if (m_penalty_weight > 0.0)
            for (int v : model.bc_indices()) m_bc_slots.push_back(slot_of(v));
        m_U_V.resize(3 * Index(m_vertices.size()), m_split.pca_dim());
        for (size_t a = 0; a < m_vertices.size(); ++a)
            m_U_V.middleRows<3>(3 * Index(a)) = m_split.basis().middleRows<3>(3 * Index(m_vertices[a]));
        m_c_V.resize(m_U_V.rows());
        m_grad_V.resize(m_U_V.rows());
    }
}

double FultonIntegrator::mean_iterations() const
{
    double sum = 0.0;
    for (const SolveSummary& s : m_summaries) sum += s.iterations;
    return m_summaries.empty() ? 0.0 : sum / double(m_summaries.size());
}

double FultonIntegrator::mean_evaluations() const
{
    double sum = 0.0;
    for (const SolveSummary& s : m_summaries) sum += s.evaluations;
    return m_summaries.empty() ? 0.0 : sum / double(m_summaries.size());
}

void FultonIntegrator::reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
                             const BoundaryState& bc_prev)
{
    std::tie(m_z_prev, m_z) = m_autoencoder->encode_pair(x_prev2, x_prev);
    m_s_prev2 = m_split.inner(m_z_prev);
    m_s_prev = m_split.inner(m_z);
    m_t_prev2 = bc_prev2.targets;
    m_t_prev = bc_prev.targets;
    m_x.resize(x_prev.size());
    m_split.offset_into(m_t_prev, m_x);
    m_x.noalias() += m_split.basis() * m_s_prev;
    update_preconditioner(m_z, m_x);
}

void FultonIntegrator::update_preconditioner(const VectorXd& z, const VectorXd& x)
{
    // Chain rule for the Gauss–Newton Hessian of Φ(z) = φ(U g(z) + c):
    //   ∇²Φ ≈ J_gᵀ Uᵀ ∇²φ U J_g, the second derivatives of g dropped; ∇²φ = M/h² (inertia,
    //   precomputed as UᵀMU) + PSD-projected elastic element Hessians + 2 w_bc on B.
    const double h2 = m_model.dt() * m_model.dt();
    const MatrixXd& U = m_split.basis();
    const Index d = m_split.pca_dim();
    MatrixXd H = m_split.mass_pca() / h2;
    double He[3 * kMaxNodes * 3 * kMaxNodes];
    MatrixXd U_e;
    auto add_element = [&](const Energy& energy, Index e, double weight) {
        const int K = energy.nodes_per_element();
        const int* nodes = energy.element_nodes(e);
        energy.element_hessian(e, x, true, He);
        U_e.resize(3 * K, d);
        for (int k = 0; k < K; ++k) U_e.middleRows<3>(3 * k) = U.middleRows<3>(3 * Index(nodes[k]));
        const Eigen::Map<const MatrixXd> Hm(He, 3 * K, 3 * K);
        H.noalias() += weight * U_e.transpose() * (Hm * U_e);
    };
    if (m_cubature) {
        for (const CubatureElement& c : m_cubature->elements)
            add_element(*m_model.elastic_terms()[size_t(c.term)], c.element, c.weight);
    } else {
        for (const auto& term : m_model.elastic_terms())
            for (Index e = 0; e < term->num_elements(); ++e) add_element(*term, e, 1.0);
    }
    if (m_penalty_weight > 0.0)
        for (int v : m_model.bc_indices())
            H.noalias() += 2.0 * m_penalty_weight * U.middleRows<3>(3 * Index(v)).transpose() * U.middleRows<3>(3 * Index(v));
    const MatrixXd J = m_split.inner_jacobian(z);
    MatrixXd Hz = J.transpose() * H * J;
    Hz.diagonal().array() += 1e-10 * std::max(Hz.diagonal().maxCoeff(), 1e-300);
    const Eigen::LLT<MatrixXd> llt(Hz);
    const Index n = Hz.rows();
    if (llt.info() != Eigen::Success || !Hz.allFinite()) {
        m_P = MatrixXd::Identity(n, n);  // no usable curvature: L-BFGS unpreconditioned
    } else {
        // P = L⁻ᵀ, so Pᵀ Hz P = I.
        m_P = llt.matrixU().solve(MatrixXd::Identity(n, n));
    }
    m_steps_since_preconditioner = 0;
}

void FultonIntegrator::prepare_step(const BoundaryState& bc)
{
    const double h2 = m_model.dt() * m_model.dt();
    m_targets = bc.targets;
    m_s_tilde = 2.0 * m_s_prev - m_s_prev2;
    const VectorXd dt_targets = m_targets - 2.0 * m_t_prev + m_t_prev2;
    m_q.noalias() = m_split.mass_targets() * dt_targets;
    VectorXd dc(m_model.num_dofs());
    m_split.target_offset_into(dt_targets, dc);
    double inertia_constant = 0.0;
    for (Index i = 0; i < m_model.num_vertices(); ++i)
        inertia_constant += m_model.masses()[i] * dc.segment<3>(3 * i).squaredNorm();
    m_c.resize(m_model.num_dofs());
    m_split.offset_into(m_targets, m_c);
    m_constant = inertia_constant / (2.0 * h2) - m_split.mass_gravity().dot(m_c);
    if (m_cubature)
        for (size_t a = 0; a < m_vertices.size(); ++a) m_c_V.segment<3>(3 * Index(a)) = m_c.segment<3>(3 * Index(m_vertices[a]));
}

double FultonIntegrator::evaluate(const Eigen::Ref<const VectorXd>& z, VectorXd* grad_z)
{
    const double h2 = m_model.dt() * m_model.dt();
    const VectorXd s = m_split.inner(z);
    const VectorXd ds = s - m_s_tilde;
    const VectorXd K_ds = m_split.mass_pca() * ds;
    double E = (ds.dot(K_ds) + 2.0 * ds.dot(m_q)) / (2.0 * h2) - m_split.gravity_pca().dot(s) + m_constant;
    VectorXd grad_s = (K_ds + m_q) / h2 - m_split.gravity_pca();
    const Index B = Index(m_model.bc_indices().size());
    if (m_cubature) {
        // Decode only V into the full-size buffer the element energies read from.
        const VectorXd x_V = m_U_V * s + m_c_V;
        for (size_t a = 0; a < m_vertices.size(); ++a)
            m_x_buffer.segment<3>(3 * Index(m_vertices[a])) = x_V.segment<3>(3 * Index(a));
        m_grad_V.setZero();
        double g[3 * kMaxNodes];
        const int* slots = m_element_slots.data();
        for (const CubatureElement& c : m_cubature->elements) {
            const Energy& energy = *m_model.elastic_terms()[size_t(c.term)];
            const int K = energy.nodes_per_element();
            E += c.weight * energy.element_value(c.element, m_x_buffer);
            if (grad_z) {
                energy.element_gradient(c.element, m_x_buffer, g);
                for (int k = 0; k < K; ++k)
                    m_grad_V.segment<3>(3 * Index(slots[k])) += c.weight * Eigen::Map<const Vector3d>(g + 3 * k);
            }
            slots += K;
        }
        for (Index b = 0; b < Index(m_bc_slots.size()); ++b) {
            const Vector3d r = x_V.segment<3>(3 * Index(m_bc_slots[size_t(b)])) - m_targets.segment<3>(3 * b);
            E += m_penalty_weight * r.squaredNorm();
            m_grad_V.segment<3>(3 * Index(m_bc_slots[size_t(b)])) += 2.0 * m_penalty_weight * r;
        }
        if (grad_z) grad_s.noalias() += m_U_V.transpose() * m_grad_V;
    } else {
        m_x_buffer = m_c;
        m_x_buffer.noalias() += m_split.basis() * s;
        for (const auto& term : m_model.elastic_terms()) E += term->value(m_x_buffer);
        if (grad_z) {
            m_grad_x.setZero(m_x_buffer.size());
            for (const auto& term : m_model.elastic_terms()) term->add_gradient(m_x_buffer, 1.0, m_grad_x);
        }
        if (m_penalty_weight > 0.0) {
            for (Index b = 0; b < B; ++b) {
                const Index v = m_model.bc_indices()[size_t(b)];
                const Vector3d r = m_x_buffer.segment<3>(3 * v) - m_targets.segment<3>(3 * b);
                E += m_penalty_weight * r.squaredNorm();
                if (grad_z) m_grad_x.segment<3>(3 * v) += 2.0 * m_penalty_weight * r;
            }
        }
        if (grad_z) grad_s.noalias() += m_split.basis().transpose() * m_grad_x;
    }
    if (grad_z) *grad_z = m_split.vjp(grad_s);
    return E;
}

double FultonIntegrator::objective(const VectorXd& z, const BoundaryState& bc, VectorXd* gradient)
{
    prepare_step(bc);
    VectorXd g;
    const double E = evaluate(z, gradient ? &g : nullptr);
    if (gradient) *gradient = g;
    return E;
}

double FultonIntegrator::reference_objective(const VectorXd& z, const BoundaryState& bc)
{
    const Index n = m_model.num_dofs();
    VectorXd x_prev(n), x_prev2(n);
    m_split.offset_into(m_t_prev, x_prev);
    x_prev.noalias() += m_split.basis() * m_s_prev;
    m_split.offset_into(m_t_prev2, x_prev2);
    x_prev2.noalias() += m_split.basis() * m_s_prev2;
    LatentPotential potential(m_model, *m_autoencoder, m_options.penalty_weight);
    return potential.value(z, bc.targets, x_prev, x_prev2);
}

StepTiming FultonIntegrator::step(const BoundaryState& bc)
{
    Timer timer;
    prepare_step(bc);
    if (m_options.preconditioner_refresh > 0 && m_steps_since_preconditioner >= m_options.preconditioner_refresh &&
        m_x.allFinite())
        update_preconditioner(m_z, m_x);
    ++m_steps_since_preconditioner;
    StepObjective objective(*this);
    m_z_start = 2.0 * m_z - m_z_prev;  // warm start: constant latent velocity
    VectorXd y = VectorXd::Zero(m_z.size());
    SolveSummary summary = minimize_lbfgs(objective, y, m_lbfgs, &m_workspace);
    if (summary.termination == SolveTermination::NonFinite && summary.iterations == 0) {
        m_z_start = m_z;  // the extrapolated start is not finite: start from the previous latent
        y.setZero();
        summary = minimize_lbfgs(objective, y, m_lbfgs, &m_workspace);
    }
    VectorXd z = objective.latent(y);
    if (!summary.converged() && summary.termination != SolveTermination::NonFinite &&
        summary.termination != SolveTermination::MaxEvaluations && z.allFinite()) {
        // NLopt gave up (typically its first line search: the preconditioner of an earlier
        // state is off here): once more from the best point, with the curvature there.
        VectorXd x(m_c.size());
        x = m_c;
        x.noalias() += m_split.basis() * m_split.inner(z);
        update_preconditioner(z, x);
        m_z_start = z;
        y.setZero();
        const SolveSummary first = summary;
        summary = minimize_lbfgs(objective, y, m_lbfgs, &m_workspace);
        summary.iterations += first.iterations;
        summary.evaluations += first.evaluations;
        summary.seconds += first.seconds;
        summary.message = "retried with a fresh preconditioner after: " + to_string(first.termination) +
                          (first.message.empty() ? "" : " (" + first.message + ")") +
                          (summary.message.empty() ? "" : "; " + summary.message);
        z = objective.latent(y);
    }
    const bool blown_up = summary.termination == SolveTermination::NonFinite || !z.allFinite();
    VectorXd s = blown_up ? VectorXd::Constant(m_split.pca_dim(), kNaN) : m_split.inner(z);
    if (blown_up) z.setConstant(kNaN);
    if (!summary.converged()) {
        if (m_unconverged == 0)
            log_warn("%s '%s': an L-BFGS step solve stopped before converging (%s; the total is reported after the "
                     "rollouts)",
                     m_cubature ? "fulton_cubature" : "fulton_full", m_name.c_str(), summary.brief().c_str());
        ++m_unconverged;
    }
    m_summaries.push_back(summary);
    m_z_prev = m_z;
    m_z = z;
    m_s_prev2.swap(m_s_prev);
    m_s_prev = s;
    m_t_prev2.swap(m_t_prev);
    m_t_prev = m_targets;
    const double integrate = timer.seconds();
    Timer decode;
    m_x = m_c;
    m_x.noalias() += m_split.basis() * s;
    return {integrate, decode.seconds()};
}

} // namespace lb
