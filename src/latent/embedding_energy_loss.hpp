#pragma once
// The physics term of an embedding (Tan, Pan, Gao & Manocha, §IV, L_ephys) and the
// reconstruction term beside it, over the training frames of a dataset:
//
//   L_recon = Σ_b ‖D(E(x_b)) − x_b‖² / (3N · B)             position MSE per DOF
//   L_ephys = c_E Σ_b E(D(E(x_m)); x̂_{m−1}, x̂_{m−2}, x*_m) / B,  x̂_k = sg(D(E(x_k)))
//
// over frames m ≥ 2 of every sequence's training window; E is the implicit-Euler
// incremental potential with the Dirichlet penalty (latent_potential.hpp), with the
// stop-gradient of Tan's eq. 5 on the two previous frames; gradients reach the decoder
// and the encoder. c_E = 2h² / (3N m̄) puts E in the units of L_recon: the inertia term
// becomes the per-DOF mean squared distance to x̃ = 2x_{m−1} − x_{m−2} in units of the
// mean vertex mass. Constant offsets (gravity) do not change gradients; a value may be
// negative.
//
// Two users: Tan et al.'s stage 1 and 3 (baselines/tan_physics_mlp/), and the
// autoencoder option physics_epochs (autoencoder.hpp), which fine-tunes a trained
// autoencoder with λ_recon L_recon + λ_ephys L_ephys so that decoded ground truth stores
// less spurious energy. The autoencoder runs in eval mode (BatchNorm with its running
// statistics, not updated; its affine weights train): the loss sees exactly the embedding
// that rollouts decode, and each sample's loss is independent of its batch.
#include <functional>
#include <vector>

#include "latent/autoencoder.hpp"
#include "latent/latent_potential.hpp"
#include "nn/training_loop.hpp"
#include "sim/dataset.hpp"
#include "sim/physics_model.hpp"

namespace lb {

/// The training frames of one sequence (columns are frames 0 … train_frames−1).
struct FrameSequence {
    MatrixXd X;        ///< 3N × T positions
    MatrixXd targets;  ///< 3B × T Dirichlet targets
    MatrixXd params;   ///< P × T boundary parameters
    Index frames() const { return X.cols(); }
};

/// A frame of a sequence (or the start of a window of frames).
struct FrameSample {
    Index sequence = 0;
    Index frame = 0;
};

/// Which columns FrameSequence::gather reads.
enum class FrameColumn { positions, targets, params };

/// The two terms, unweighted means.
struct EmbeddingLossParts {
    double recon = 0.0, ephys = 0.0;
};

class EmbeddingEnergyLoss {
public:
    /// @param model           physics (must outlive this object)
    /// @param data            its training frames are copied (sequences with < 3 are skipped)
    /// @param autoencoder     the embedding the loss trains (must outlive this object)
    /// @param penalty_weight  configured w_bc (> 0; applied_penalty_weight: 0 for rods)
    /// @param who             names the caller in errors ("tan_physics_mlp", "autoencoder")
    /// Throws ConfigError if no sequence has 3 training frames.
    EmbeddingEnergyLoss(const PhysicsModel& model, const Dataset& data, Autoencoder& autoencoder,
                        double penalty_weight, const std::string& who);

    const PhysicsModel& model() const { return m_model; }
    Autoencoder& autoencoder() { return m_ae; }
    LatentPotential& potential() { return m_potential; }
    const std::vector<FrameSequence>& sequences() const { return m_sequences; }
    /// Every frame m ≥ 2 of the training window of every sequence.
    std::vector<FrameSample> frame_samples() const;
    /// c_E = 2h² / (3N m̄).
    double energy_scale() const { return m_energy_scale; }
    /// Per-DOF masses (3N).
    const VectorXd& dof_masses() const { return m_dof_masses; }

    /// Columns of frames m + offset of the batch.
    MatrixXd gather(const std::vector<FrameSample>& batch, Index offset, FrameColumn which) const;
    /// Targets of [frame m, m−1, m−2] of the batch (3B × 3·batch).
    MatrixXd triple_targets(const std::vector<FrameSample>& batch) const;
    /// Encoder (eval mode) on [x_m, x_{m−1}, x_{m−2}] of the batch: latent × 3·batch; the
    /// encoder's cache is kept for a backward pass.
    MatrixXd encode_triples(const std::vector<FrameSample>& batch);

    /// recon_weight L_recon + ephys_weight L_ephys of decoded frames X_hat (3N × 3B:
    /// [x̂_m, x̂_{m−1}, x̂_{m−2}]); with `gradient`, grad_x (3N × B) is the weighted loss's
    /// gradient with respect to the x̂_m columns (the other two are stopped).
    double position_losses(const MatrixXd& X_hat, const std::vector<FrameSample>& batch, double recon_weight,
                           double ephys_weight, bool gradient, MatrixXd& grad_x, EmbeddingLossParts& parts);

    /// recon_weight L_recon + ephys_weight L_ephys of the embedding over frames `batch`;
    /// with `gradient`, the encoder's and decoder's parameter gradients are ACCUMULATED.
    double loss(const std::vector<FrameSample>& batch, double recon_weight, double ephys_weight, bool gradient,
                EmbeddingLossParts* parts = nullptr);

private:
    const PhysicsModel& m_model;
    Autoencoder& m_ae;
    LatentPotential m_potential;
    std::vector<FrameSequence> m_sequences;
    VectorXd m_dof_masses;
    double m_energy_scale = 1.0;
};

/// A loss over FrameSamples as seen by the shared training loop (nn/training_loop.hpp).
class FrameSampleLearner final : public nn::Learner {
public:
    using LossFn = std::function<double(const std::vector<FrameSample>&)>;
    FrameSampleLearner(std::vector<FrameSample> samples, std::vector<nn::ParameterRef> parameters, LossFn loss);
    Index num_samples() const override { return Index(m_samples.size()); }
    std::vector<nn::ParameterRef> parameters() override { return m_parameters; }
    double loss_and_gradient(const std::vector<Index>& indices, Rng& rng) override;

private:
    std::vector<FrameSample> m_samples;
    std::vector<nn::ParameterRef> m_parameters;
    LossFn m_loss;
};

/// The encoder's and decoder's trainable parameters, names prefixed.
std::vector<nn::ParameterRef> autoencoder_parameters(Autoencoder& ae, const std::string& prefix);

} // namespace lb
