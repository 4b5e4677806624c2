#pragma once
// The latent integrator of Li et al. 2025 §3.3:
//   z_t = I(z_{t−1}, z_{t−2}, p_t, p_{t−1}, p_{t−2}),
// an MLP with Swish on standardised inputs (training statistics). We
// parametrise its output as an increment,
//   z_t = z_{t−1} + s ⊙ MLP(standardise([z_{t−1}, z_{t−2}, p_t, p_{t−1}, p_{t−2}])),
// with s the per-component standard deviation of z_t − z_{t−1} in the training
// data: a fixed skip connection and output scale, so the same function class
// as the paper's, with a well-scaled output at initialisation.
//
// Inference runs the integrator and the decoder through the float
// InferenceNetwork (BatchNorm folded, no allocation per step), their weights streamed as
// f32 (default), f16 or int8 (`rollout --weights`, nn/weight_format.hpp). A model trained with
// overwrite_dirichlet reports positions whose Dirichlet vertices are the frame's targets;
// one whose p_t holds the boundary pose computes it each step (a 3×3 SVD, allocating).
#include <memory>

#include "integrators/integrator.hpp"
#include "io/hdf5.hpp"
#include "latent/autoencoder.hpp"
#include "latent/boundary_input.hpp"
#include "nn/inference_network.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/standardizer.hpp"

namespace lb {

/// The trainable part: network, input standardiser and output scale.
struct LatentMlpModel {
    Index latent_dim = 0;
    Index param_dim = 0;
    nn::Sequential network;    ///< in 2·latent + 3·param_dim → hidden → latent
    nn::Standardizer inputs;   ///< on the 2·latent + 3·param_dim inputs
    VectorXd output_scale;     ///< s (latent)
    std::string loss;          ///< how it was trained: "self_supervised" or "supervised_l2"
    std::string description;   ///< e.g. "noise on, balancing on"
    /// Decoded Dirichlet vertices replaced by the frame's targets (trained so; issue 14).
    bool overwrite_dirichlet = false;
    /// What p_t holds (param_dim numbers): the scene's parameters, with the boundary pose or not.
    BoundaryInput boundary;
    /// forward/backward's buffers (storage that only grows): standardised inputs, output,
    /// the output's adjoint and the inputs' gradient.
    nn::GrowingMatrix<double> standardized, prediction, output_adjoint, input_gradient;

    Index input_dim() const { return 2 * latent_dim + 3 * param_dim; }
    /// Batched forward in double (training), columns are samples.
    /// @param inputs_raw  input_dim × B unstandardised; @param z_prev  latent × B
    /// @return latent × B, a view valid until the next forward (no allocation once the
    /// model's buffers have seen the batch sizes)
    nn::BatchView forward(const Eigen::Ref<const MatrixXd>& inputs_raw, const Eigen::Ref<const MatrixXd>& z_prev,
                          bool training);
    /// Backward of the last forward: dZ (latent × B) → accumulates parameter gradients.
    /// Returns ∂L/∂inputs_raw (input_dim × B, a view valid until the next backward) through
    /// the network and the standardiser; the skip connection's term (∂L/∂z_prev += dZ) is
    /// the caller's, as z_prev is passed apart.
    nn::BatchView backward(const Eigen::Ref<const MatrixXd>& dZ);

    static LatentMlpModel create(Index latent_dim, Index param_dim, const std::vector<Index>& hidden,
                                 std::uint64_t seed);
    void save(h5::File& file, const std::string& prefix);
    static LatentMlpModel load(const h5::File& file, const std::string& prefix);
};

/// Assemble the integrator input [z1, z2, p_t, p1, p2] for one sample.
VectorXd integrator_input(const VectorXd& z_prev, const VectorXd& z_prev2, const VectorXd& p,
                          const VectorXd& p_prev, const VectorXd& p_prev2);

class LatentMlpIntegrator final : public Integrator {
public:
    /// @param name     label in tables (e.g. "ours", "supervised_l2")
    /// @param weights  what the integrator's and decoder's inference networks stream (f32, f16, int8)
    LatentMlpIntegrator(std::string name, std::shared_ptr<Autoencoder> autoencoder, LatentMlpModel model,
                        nn::WeightFormat weights = nn::WeightFormat::f32);

    std::string name() const override { return m_name; }
    void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
               const BoundaryState& bc_prev) override;
    StepTiming step(const BoundaryState& bc) override;
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_z; }

    /// Latent step alone in float (for benchmarks): z_t from the current state.
    void integrate_only(const BoundaryState& bc);
    /// Decode the current latent alone (for benchmarks).
    void decode_only(const BoundaryState& bc);

private:
    /// p_t of the frame: bc.params, or (boundary pose) those with the pose, in m_p.
    const VectorXd& boundary_params(const BoundaryState& bc);

    std::string m_name;
    std::shared_ptr<Autoencoder> m_autoencoder;
    LatentMlpModel m_model;
    nn::InferenceNetwork m_integrator_net;  ///< standardiser folded in
    nn::InferenceNetwork m_decoder_net;
    Eigen::VectorXf m_input, m_scale, m_z1f, m_zf;
    VectorXd m_z, m_z1, m_z2, m_p, m_p1, m_p2, m_x;
    Eigen::VectorXf m_features;
};

} // namespace lb
