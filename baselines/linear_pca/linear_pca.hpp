#pragma once
// `linear_pca` baseline: Newton in a linear PCA subspace, the classic reduced
// model (DESIGN §4, "Baselines").
//
// Subspace: the d leading principal directions U (F × d) and mean μ of the
// boundary-relative features of the training frames (latent/bc_encoding.hpp, the
// same features the autoencoder sees), so
//   x(q) = P (μ + U q) + offset(bc_t) = J q + c_t,   J = P U (3N × d, orthonormal columns).
// Step: q_t = argmin_q E(x(q)), E the incremental potential of implicit Euler with
// x_{t−1}, x_{t−2} the previous subspace states; for cloth and solids with the
// Dirichlet penalty w_bc Σ_B |x_i − x*_i|² (the subspace cannot pin vertices), for
// rods with the roots prescribed by the encoding. Newton (minimize_newton,
// solver/newton.hpp) on the reduced objective f(q) = E(J q + c_t),
//   g = Jᵀ∇E,  H = Jᵀ ∇²E J  (exact first, element Hessians projected to PSD on failure),
// d × d dense, with Armijo backtracking; converged when ||g|| ≤ gradient_tolerance ·
// force scale (J has orthonormal columns, so this is the full-space test restricted to
// the subspace) or the step moves no vertex by more than step_tolerance · length scale.
// Every step costs full-space energy, gradient and Hessian evaluations: no cubature.
#include <memory>
#include <string>

#include "energy/hessian_assembler.hpp"
#include "integrators/integrator.hpp"
#include "latent/autoencoder.hpp"  // training_frames
#include "latent/bc_encoding.hpp"
#include "latent/pca.hpp"
#include "sim/dataset.hpp"
#include "solver/newton.hpp"

namespace lb::h5 {
class File;
}

namespace lb {

struct LinearPcaOptions {
    Index dim = 4;                ///< subspace dimension d (clamped to the data's rank)
    double penalty_weight = 1e5;  ///< w_bc (cloth, solids; rods use hard roots)
    /// Reduced Newton iterations per step; the other Newton settings are
    /// NewtonOptions' defaults.
    int max_iterations = 50;
    /// Converged when ||Jᵀ∇E|| ≤ gradient_tolerance · force scale (PhysicsModel::force_scale).
    double gradient_tolerance = 1e-8;
    /// Converged when a step moves no vertex by more than step_tolerance · length scale.
    double step_tolerance = 1e-9;
};

/// The subspace: PCA of the BC-relative features of a dataset's training frames.
struct LinearPcaSubspace {
    PcaBasis pca;

    /// @throws ConfigError if dim < 1 or the dataset has fewer than 2 training frames
    static LinearPcaSubspace fit(const Dataset& data, Index dim);
    /// Into an open file (a method artefact, methods/artefact.hpp): datasets
    /// linear_pca.mean (F), linear_pca.basis (F × d), linear_pca.variances (d); attributes
    /// linear_pca.format "latentbench.linear_pca/1", linear_pca.total_variance,
    /// linear_pca.explained_variance.
    void save(h5::File& file) const;
    /// IoError naming the file if it holds no subspace or F does not match the scene.
    static LinearPcaSubspace load(const h5::File& file, const PhysicsSpec& physics);
};

class LinearPcaIntegrator final : public Integrator {
public:
    LinearPcaIntegrator(std::string name, const PhysicsModel& model, LinearPcaSubspace subspace, LinearPcaOptions options);

    std::string name() const override { return m_name; }
    void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
               const BoundaryState& bc_prev) override;
    /// All of it counts as integration: every Newton iteration decodes x = J q + c_t
    /// to evaluate the full-space energy, so there is no separate decode.
    StepTiming step(const BoundaryState& bc) override;
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_q; }

    /// The reduced objective E(J q + c) and its gradient Jᵀ∇E for the current step's
    /// potential (after reset(), for the boundary `bc`): exposed for derivative tests.
    double reduced_value(const VectorXd& q, const BoundaryState& bc, VectorXd* gradient);
    /// Steps (since construction, over every reset) whose Newton solve did not
    /// converge (iteration cap, failed line search or factorisation, non-finite state).
    int unconverged_steps() const { return m_unconverged; }
    Index dim() const { return m_J.cols(); }
    /// Mean reduced Newton iterations per step since construction.
    double mean_iterations() const { return m_steps ? double(m_iterations) / double(m_steps) : 0.0; }

private:
    /// Project full positions onto the subspace (least squares: Jᵀ(x − c)).
    VectorXd project(const VectorXd& x, const BoundaryState& bc) const;
    /// c_t: the positions of q = 0 under the boundary targets.
    VectorXd offset(const BoundaryState& bc) const;
    void prepare_step(const BoundaryState& bc);

    std::string m_name;
    const PhysicsModel& m_model;
    LinearPcaSubspace m_subspace;
    LinearPcaOptions m_options;
    BcRelativeEncoding m_encoding;
    IncrementalPotential m_potential;
    std::unique_ptr<HessianAssembler> m_assembler;
    NewtonOptions m_newton;  ///< from m_options and the model's scales
    NewtonWorkspace m_workspace;
    MatrixXd m_J;  ///< 3N × d
    VectorXd m_q, m_q_prev, m_x, m_x_prev, m_x_prev2, m_c;
    int m_unconverged = 0;
    long m_steps = 0, m_iterations = 0;
};

} // namespace lb
