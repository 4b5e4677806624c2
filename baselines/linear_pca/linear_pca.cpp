#include "baselines/linear_pca/linear_pca.hpp"

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"

namespace lb {

namespace {
constexpr const char* kFormat = "latentbench.linear_pca/1";

/// One step's reduced problem over the subspace coordinates q (d):
///   f(q) = E(J q + c),  ∇f = Jᵀ∇E,  ∇²f = Jᵀ ∇²E J  (d × d, dense),
/// E the incremental potential, ∇²E assembled over every DOF (prescribed rows of J
/// are zero). A view for one step: the references must outlive it.
class ReducedObjective final : public Objective {
public:
    ReducedObjective(const MatrixXd& J, const VectorXd& c, const IncrementalPotential& potential,
                     HessianAssembler& assembler)
        : m_J(J), m_c(c), m_potential(potential), m_assembler(assembler)
    {
    }

    /// x = J q + c (3N), valid until the next evaluation.
    const VectorXd& decode(const Eigen::Ref<const VectorXd>& q)
    {
        m_x.noalias() = m_J * q;
        m_x += m_c;
        return m_x;
    }

    Index dimension() const override { return m_J.cols(); }
    double value(const Eigen::Ref<const VectorXd>& q) override { return m_potential.value(decode(q)); }
    void gradient(const Eigen::Ref<const VectorXd>& q, Eigen::Ref<VectorXd> g) override
    {
        g.noalias() = m_J.transpose() * m_potential.gradient(decode(q));
    }
    HessianKind hessian_kind() const override { return HessianKind::Dense; }
    void dense_hessian(const Eigen::Ref<const VectorXd>& q, bool project_psd, MatrixXd& H) override
    {
        m_assembler.assemble(m_potential.terms(), decode(q), project_psd);
        H.noalias() = m_J.transpose() * (m_assembler.matrix().selfadjointView<Eigen::Lower>() * m_J);
    }
    /// The largest vertex displacement of a step: ||J dq||_∞.
    double step_length(const Eigen::Ref<const VectorXd>& dq) override { return (m_J * dq).cwiseAbs().maxCoeff(); }

private:
    const MatrixXd& m_J;
    const VectorXd& m_c;
    const IncrementalPotential& m_potential;
    HessianAssembler& m_assembler;
    VectorXd m_x;
};
} // namespace

LinearPcaSubspace LinearPcaSubspace::fit(const Dataset& data, Index dim)
{
    if (dim < 1) throw ConfigError("linear_pca: dim must be at least 1 (got " + std::to_string(dim) + ")");
    const FrameSet frames = training_frames(data);
    if (frames.positions.cols() < 2)
        throw ConfigError("linear_pca: the dataset has " + std::to_string(frames.positions.cols()) +
                          " training frames; the PCA needs at least 2");
    const BcRelativeEncoding encoding(data.physics);
    const MatrixXd features = encoding.to_features(frames.positions);
    LinearPcaSubspace s;
    s.pca = compute_pca(features, std::min<Index>(dim, std::min<Index>(features.rows(), features.cols() - 1)));
    return s;
}

void LinearPcaSubspace::save(h5::File& f) const
{
    f.write("linear_pca.mean", pca.mean);
    f.write("linear_pca.basis", pca.basis);
    f.write("linear_pca.variances", pca.variances);
    f.set_attribute("/", "linear_pca.format", std::string(kFormat));
    f.set_attribute("/", "linear_pca.total_variance", pca.total_variance);
    f.set_attribute("/", "linear_pca.explained_variance", pca.explained_fraction());
}

LinearPcaSubspace LinearPcaSubspace::load(const h5::File& f, const PhysicsSpec& physics)
{
    const std::string& path = f.path();
    if (!f.has_attribute("/", "linear_pca.format") || f.attribute_string("/", "linear_pca.format") != kFormat)
        throw IoError(path + ": holds no linear_pca subspace (attribute linear_pca.format is not '" +
                      std::string(kFormat) + "')");
    LinearPcaSubspace s;
    s.pca.mean = f.read_vector("linear_pca.mean");
    s.pca.basis = f.read_matrix("linear_pca.basis");
    s.pca.variances = f.read_vector("linear_pca.variances");
    s.pca.total_variance = f.attribute_double("/", "linear_pca.total_variance");
    const Index F = BcRelativeEncoding(physics).num_features();
    // Each dataset on its own, so that the message names the one that is wrong.
    const auto fail = [&](const std::string& name, const std::string& problem) {
        throw IoError(path + ": dataset 'linear_pca." + name + "' " + problem);
    };
    if (s.pca.mean.size() != F)
        fail("mean", "has " + std::to_string(s.pca.mean.size()) + " entries; the scene has " + std::to_string(F) +
                         " features");
    if (s.pca.basis.rows() != F || s.pca.basis.cols() < 1)
        fail("basis", "is " + std::to_string(s.pca.basis.rows()) + "×" + std::to_string(s.pca.basis.cols()) +
                          "; expected " + std::to_string(F) + " rows (the scene's features) and at least one column");
    if (s.pca.variances.size() != s.pca.basis.cols())
        fail("variances", "has " + std::to_string(s.pca.variances.size()) + " entries for the " +
                              std::to_string(s.pca.basis.cols()) + " columns of 'linear_pca.basis'");
    if (!s.pca.mean.allFinite()) fail("mean", "holds non-finite values (NaN or inf)");
    if (!s.pca.basis.allFinite()) fail("basis", "holds non-finite values (NaN or inf)");
    if (!s.pca.variances.allFinite() || (s.pca.variances.array() < 0.0).any())
        fail("variances", "holds values that are not finite and ≥ 0 (NaN, inf or negative)");
    if (!std::isfinite(s.pca.total_variance) || s.pca.total_variance < 0.0)
        throw IoError(path + ": attribute 'linear_pca.total_variance' is not finite and ≥ 0");
    return s;
}

LinearPcaIntegrator::LinearPcaIntegrator(std::string name, const PhysicsModel& model, LinearPcaSubspace subspace,
                                         LinearPcaOptions options)
    : m_name(std::move(name)),
      m_model(model),
      m_subspace(std::move(subspace)),
      m_options(options),
      m_encoding(model.spec()),
      m_potential(model, applied_penalty_weight(model, options.penalty_weight))
{
    const PcaBasis& pca = m_subspace.pca;
    if (pca.basis.rows() != m_encoding.num_features())
        throw ConfigError("linear_pca: the subspace has " + std::to_string(pca.basis.rows()) +
                          " features, the scene " + std::to_string(m_encoding.num_features()));
    // x = P f + offset(targets) is affine in f: J = P U is the image of U with zero targets.
    const Index B = Index(m_encoding.bc_indices().size());
    const MatrixXd zero_targets = MatrixXd::Zero(3 * B, pca.dim());
    m_J = m_encoding.to_positions(pca.basis, zero_targets);
    // Every DOF is an unknown of the full-space Hessian; rows of prescribed DOFs of J are zero.
    VectorXi all = VectorXi::LinSpaced(model.num_dofs(), 0, int(model.num_dofs() - 1));
    m_assembler = std::make_unique<HessianAssembler>(all, m_potential.terms());
    m_newton.max_iterations = options.max_iterations;
    m_newton.gradient_tolerance = options.gradient_tolerance;
    m_newton.step_tolerance = options.step_tolerance;
    m_newton.force_scale = model.force_scale();
    m_newton.length_scale = model.length_scale();
}

VectorXd LinearPcaIntegrator::offset(const BoundaryState& bc) const
{
    VectorXd c(m_model.num_dofs());
    m_encoding.to_positions_into(m_subspace.pca.mean, bc.targets, c);
    return c;
}

VectorXd LinearPcaIntegrator::project(const VectorXd& x, const BoundaryState& bc) const
{
    return m_J.transpose() * (x - offset(bc));
}

void LinearPcaIntegrator::reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
                                const BoundaryState& bc_prev)
{
    // Start from the subspace states closest to the two given frames.
    const VectorXd q2 = project(x_prev2, bc_prev2);
    m_q = project(x_prev, bc_prev);
    m_q_prev = q2;
    m_x_prev2 = m_J * q2 + offset(bc_prev2);
    m_x_prev = m_J * m_q + offset(bc_prev);
    m_x = m_x_prev;
}

void LinearPcaIntegrator::prepare_step(const BoundaryState& bc)
{
    m_potential.set_previous(m_x_prev, m_x_prev2);
    if (m_potential.has_penalty()) m_potential.set_bc_targets(as_rows(bc.targets));
    m_c.resize(m_model.num_dofs());
    m_encoding.to_positions_into(m_subspace.pca.mean, bc.targets, m_c);
}

double LinearPcaIntegrator::reduced_value(const VectorXd& q, const BoundaryState& bc, VectorXd* gradient)
{
    prepare_step(bc);
    ReducedObjective objective(m_J, m_c, m_potential, *m_assembler);  // the one step() minimises
    if (gradient) {
        gradient->resize(dim());
        objective.gradient(q, *gradient);
    }
    return objective.value(q);
}

StepTiming LinearPcaIntegrator::step(const BoundaryState& bc)
{
    Timer timer;
    prepare_step(bc);
    ReducedObjective objective(m_J, m_c, m_potential, *m_assembler);
    // Warm start: constant-velocity extrapolation in the subspace.
    VectorXd q = 2.0 * m_q - m_q_prev;
    ++m_steps;
    SolveSummary summary = minimize_newton(objective, q, m_newton, &m_workspace);
    if (summary.termination == SolveTermination::NonFinite && summary.iterations == 0) {
        q = m_q;  // the extrapolated start is not finite: start from the previous state
        summary = minimize_newton(objective, q, m_newton, &m_workspace);
    }
    m_iterations += summary.iterations;
    VectorXd x;
    if (summary.termination == SolveTermination::NonFinite) {
        // The subspace state blew up: report a non-finite state, which ends the
        // rollout's stable horizon (eval/rollout.cpp) instead of aborting a suite.
        q.setConstant(std::numeric_limits<double>::quiet_NaN());
        x.setConstant(m_model.num_dofs(), std::numeric_limits<double>::quiet_NaN());
    } else {
        x = objective.decode(q);
    }
    if (!summary.converged()) {
        if (m_unconverged == 0)
            log_warn("linear_pca '%s': a reduced Newton solve stopped before converging (%s; the total is reported "
                     "after the rollouts)",
                     m_name.c_str(), summary.brief().c_str());
        ++m_unconverged;
    }
    m_q_prev = m_q;
    m_q = q;
    m_x_prev2.swap(m_x_prev);
    m_x_prev = x;
    m_x.swap(x);
    return {timer.seconds(), 0.0};
}

} // namespace lb
