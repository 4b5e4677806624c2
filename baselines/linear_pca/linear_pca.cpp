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
}

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
    if (s.pca.mean.size() != F || s.pca.basis.rows() != F || s.pca.variances.size() != s.pca.basis.cols() ||
        s.pca.basis.cols() < 1)
        throw IoError(path + ": linear_pca shapes (mean " + std::to_string(s.pca.mean.size()) + ", basis " +
                      std::to_string(s.pca.basis.rows()) + "×" + std::to_string(s.pca.basis.cols()) +
                      ") do not match the scene's " + std::to_string(F) + " features");
    if (!s.pca.basis.allFinite() || !s.pca.mean.allFinite()) throw IoError(path + ": linear_pca basis is not finite");
    return s;
}

LinearPcaIntegrator::LinearPcaIntegrator(std::string name, const PhysicsModel& model, LinearPcaSubspace subspace,
                                         LinearPcaOptions options)
    : m_name(std::move(name)),
      m_model(model),
      m_subspace(std::move(subspace)),
      m_options(options),
      m_encoding(model.spec()),
      m_potential(model, model.kind() == MeshKind::Rods ? 0.0 : options.penalty_weight)
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
    const VectorXd x = m_J * q + m_c;
    if (gradient) *gradient = m_J.transpose() * m_potential.gradient(x);
    return m_potential.value(x);
}

StepTiming LinearPcaIntegrator::step(const BoundaryState& bc)
{
    Timer timer;
    prepare_step(bc);
    const double force_tol = m_options.gradient_tolerance * m_model.force_scale();
    const double step_tol = m_options.step_tolerance * m_model.length_scale();
    // Warm start: constant-velocity extrapolation in the subspace.
    VectorXd q = 2.0 * m_q - m_q_prev;
    VectorXd x = m_J * q + m_c;
    double value = m_potential.value(x);
    if (!std::isfinite(value)) {  // fall back to the previous state
        q = m_q;
        x = m_J * q + m_c;
        value = m_potential.value(x);
    }
    bool converged = false;
    VectorXd x_try(x.size());
    ++m_steps;
    for (int it = 0; it < m_options.max_iterations && !converged; ++it) {
        const VectorXd g = m_J.transpose() * m_potential.gradient(x);
        if (!g.allFinite() || !std::isfinite(value)) {
            // The subspace state blew up: report a non-finite state, which ends the
            // rollout's stable horizon (eval/rollout.cpp) instead of aborting a suite.
            q.setConstant(std::numeric_limits<double>::quiet_NaN());
            x.setConstant(std::numeric_limits<double>::quiet_NaN());
            break;
        }
        if (g.norm() <= force_tol) {
            converged = true;
            break;
        }
        // Exact reduced Hessian first (quadratic convergence); if it is not positive
        // definite, the one of PSD-projected element Hessians, shifted if still singular.
        Eigen::LDLT<MatrixXd> ldlt;
        MatrixXd H;
        for (bool project : {false, true}) {
            m_assembler->assemble(m_potential.terms(), x, project);
            H.noalias() = m_J.transpose() * (m_assembler->matrix().selfadjointView<Eigen::Lower>() * m_J);
            ldlt.compute(H);
            if (ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all()) break;
        }
        double shift = 1e-10 * std::max(H.diagonal().cwiseAbs().maxCoeff(), 1e-300);
        while (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
            if (!H.allFinite() || shift > 1e6 * std::max(H.diagonal().cwiseAbs().maxCoeff(), 1.0))
                break;  // caught below: the step direction is not finite or not a descent
            H.diagonal().array() += shift;
            shift *= 10.0;
            ldlt.compute(H);
        }
        ++m_iterations;
        const VectorXd dq = -ldlt.solve(g);
        const double slope = g.dot(dq);
        if (!dq.allFinite() || !(slope < 0.0)) break;  // no descent direction: counted as unconverged
        double alpha = 1.0;
        bool accepted = false;
        for (int ls = 0; ls < 40; ++ls) {
            x_try.noalias() = m_J * (q + alpha * dq);
            x_try += m_c;
            const double v_try = m_potential.value(x_try);
            if (std::isfinite(v_try) && v_try <= value + 1e-4 * alpha * slope) {
                q += alpha * dq;
                x = x_try;
                value = v_try;
                accepted = true;
                break;
            }
            alpha *= 0.5;
        }
        const double moved = (alpha * (m_J * dq)).cwiseAbs().maxCoeff();
        if (!accepted || moved <= step_tol) {
            converged = accepted || moved <= step_tol;
            break;
        }
    }
    if (!converged) {
        if (m_unconverged == 0)
            log_warn("linear_pca '%s': a reduced Newton solve stopped before converging (the total is reported after the rollouts)",
                     m_name.c_str());
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
