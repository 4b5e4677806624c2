#pragma once
// Training of the latent MLP integrator (Li et al. 2025 §3.3, DESIGN §4).
//
// Losses (a switch each, so every ablation is one flag):
//   self_supervised  L_i = E(x_t(z_t); x_{t−1}, x_{t−2}) = E_I + E_elastic + E_g [+ E_bc],
//                    the full-space incremental potential of the decoded prediction, with
//                    x_{t−1}, x_{t−2} decoded from the input latents and the Dirichlet penalty
//                    w_bc Σ_B |x_i − x*_i|² for cloth and solids (rods: roots are hard).
//                    ∂L/∂z_t = J_Dᵀ ∇E: one vector-Jacobian product through the frozen
//                    decoder per sample; energies are evaluated in parallel over the batch
//                    (latent/latent_potential.hpp).
//   supervised_l2    L_i = ||z_t − z_t^gt||² (the baseline; same network).
// Data balancing: L_i / max(|v_{t−1}|, v_floor) (paper eq. 6), with |v_{t−1}| of the decoded
//   inputs v_j = (x_{t−1}^j − x_{t−2}^j)/h, j over the N vertices, either
//     mean_velocity  |(1/N) Σ_j v_j|   (the default: eq. 6 read literally), or
//     mean_speed     (1/N) Σ_j |v_j|   (a rotation about the Dirichlet centroid has mean
//                    velocity ~0 and would sit at the floor; its mean speed does not);
//   v_floor = balancing_floor × the mean |v_{t−1}| of the training samples, because the
//   formula divides by zero for a system at rest (the first frames of every sequence, a
//   cantilever at steady state).
// Training noise: every batch is doubled with copies whose z_{t−1}, z_{t−2} get uniform
//   noise U(−a, a), a = noise_fraction × the batch's per-component standard deviation;
//   boundary parameters unchanged (paper eq. 5).
// Dirichlet overwrite (overwrite_dirichlet): the decoded positions — the prediction and the
//   inputs x_{t−1}, x_{t−2}, in training and in rollouts — have their Dirichlet vertices
//   replaced by the frame's targets (LatentPotential), so the penalty is 0 and the loss has no
//   gradient through the Dirichlet rows. Off by default (the paper decodes them and penalises).
// Boundary input (boundary_input): p_t holds the scene's boundary velocities ("velocity", the
//   paper's) or those and the Dirichlet targets' rigid pose ("pose"; latent/boundary_input.hpp).
// The batch loss is the mean over its (possibly doubled) samples. Noise is an option of
//   either loss; the method parser (methods/latent_mlp) leaves it off for supervised_l2 unless
//   asked for, as in the paper, where the baseline differs from the method only in the loss.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "integrators/latent_mlp_integrator.hpp"
#include "nn/training_loop.hpp"
#include "nn/workspace.hpp"
#include "latent/latent_potential.hpp"
#include "sim/physics_model.hpp"

namespace lb {

enum class IntegratorLoss { SelfSupervised, SupervisedL2 };
std::string to_string(IntegratorLoss loss);
IntegratorLoss integrator_loss_from_string(const std::string& name);

/// Which |v_{t−1}| data balancing divides by (see above).
enum class BalancingVelocity { MeanVelocity, MeanSpeed };
std::string to_string(BalancingVelocity velocity);
BalancingVelocity balancing_velocity_from_string(const std::string& name);

/// |v_{t−1}| of data balancing for every sample (column).
/// @param X_prev, X_prev2  3N × S positions x_{t−1}, x_{t−2}
/// @param dt               time step h (s)
/// @return S speeds (m/s)
VectorXd balancing_speeds(const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2,
                          double dt, BalancingVelocity velocity);
/// The same into `speeds` (S, sized by the caller).
void balancing_speeds(const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2, double dt,
                      BalancingVelocity velocity, Eigen::Ref<VectorXd> speeds);

/// Training noise on the two input latents (issue 39; the paper does not say): an
/// independent uniform draw for z_{t−1} and for z_{t−2} (the default), or one draw u per
/// sample and component shared by both, each scaled by its own latent's batch std.
enum class NoiseDraw { Independent, Shared };
std::string to_string(NoiseDraw draw);
NoiseDraw noise_draw_from_string(const std::string& name);

struct IntegratorTrainOptions : nn::TrainingRunOptions {
    IntegratorLoss loss = IntegratorLoss::SelfSupervised;
    std::vector<Index> hidden{256, 256, 256, 256, 256};
    int epochs = 1000;
    int batch_size = 256;
    double learning_rate = 1e-4;
    bool training_noise = true;
    double noise_fraction = 0.1;
    NoiseDraw noise_draw = NoiseDraw::Independent;
    bool data_balancing = true;
    BalancingVelocity balancing_velocity = BalancingVelocity::MeanVelocity;
    double balancing_floor = 0.05;
    double penalty_weight = 1e5;  ///< w_bc (cloth, solids)
    bool overwrite_dirichlet = false;
    /// The self-supervised loss's frozen decoder in single precision (issue 14: float32
    /// where it does not change results); the energies stay double.
    bool float32_decoder = false;
    BoundaryInputKind boundary_input = BoundaryInputKind::Velocity;  ///< what p_t holds
    std::uint64_t seed = 0;
    /// One line for logs and file attributes.
    std::string describe() const;
    /// "balancing on", "balancing off" or "balancing on (mean speed)": the phrase of
    /// describe() and of table rows.
    std::string balancing_text() const;
    /// The representation switches that are not the paper's, as phrases to append (e.g.
    /// ", Dirichlet overwritten"; "" for the paper's): of describe() and of table rows.
    std::string representation_text() const;
};

/// Training samples from the training frames of a dataset: for every sequence and
/// t ∈ [2, train_frames): latents of frames t−1, t−2 (encoded ground truth), the
/// boundary parameters p of t, t−1, t−2 (as `boundary` makes them from the scene's
/// parameters and targets), the ground-truth latent of t, and the Dirichlet targets of the
/// three frames. Columns are samples.
struct TrainingSamples {
    MatrixXd z_prev, z_prev2, z_target;          ///< latent × S
    MatrixXd p, p_prev, p_prev2;                 ///< P × S
    MatrixXd targets, targets_prev, targets_prev2;  ///< 3B × S
    BoundaryInputKind boundary_input = BoundaryInputKind::Velocity;  ///< how p was made
    Index size() const { return z_prev.cols(); }
};
TrainingSamples make_training_samples(Autoencoder& ae, const Dataset& data, const BoundaryInput& boundary = {});

/// The model's input standardiser (from the samples' inputs) and output scale s (the
/// per-component standard deviation of z_t − z_{t−1}, 1 where it vanishes).
void fit_input_statistics(LatentMlpModel& model, const TrainingSamples& samples);

/// A mini-batch, after noise was (optionally) added. Its matrices are views of storage that
/// only grows: refilling one batch (IntegratorTrainer::make_batch into it) allocates nothing
/// once it has held the largest batch. Views are valid until the next refill.
class IntegratorBatch {
public:
    std::vector<Index> source;  ///< sample index of each column
    Index clean = 0;            ///< columns [0, clean) carry unperturbed ground-truth latents
    Index size() const { return Index(source.size()); }
    /// input_dim × B (unstandardised): z_{t−1}, z_{t−2}, p_t, p_{t−1}, p_{t−2} stacked.
    Eigen::Map<const MatrixXd> inputs() const { return m_inputs.view(); }
    Eigen::Map<const MatrixXd> z_prev() const { return m_z_prev.view(); }  ///< latent × B
    Eigen::Map<const MatrixXd> z_prev2() const { return m_z_prev2.view(); }
    Eigen::Map<const MatrixXd> z_target() const { return m_z_target.view(); }
    Eigen::Map<const MatrixXd> targets() const { return m_targets.view(); }  ///< 3B × B Dirichlet targets
    Eigen::Map<const MatrixXd> targets_prev() const { return m_targets_prev.view(); }
    Eigen::Map<const MatrixXd> targets_prev2() const { return m_targets_prev2.view(); }

private:
    friend class IntegratorTrainer;
    nn::GrowingMatrix<double> m_inputs, m_z_prev, m_z_prev2, m_z_target, m_targets, m_targets_prev, m_targets_prev2;
    VectorXd m_mean, m_std;  ///< the noise's per-component statistics (latent)
    MatrixXd m_draw;         ///< latent × B uniform draws shared by both latents (NoiseDraw::Shared)
};

/// What a training run did (epochs, final loss, resumed, time-limited, why a checkpoint
/// was refused): the shared loop's summary.
using IntegratorTrainSummary = nn::TrainingLoopSummary;

class IntegratorTrainer {
public:
    IntegratorTrainer(const PhysicsModel& model, Autoencoder& autoencoder, IntegratorTrainOptions options);

    /// Gather samples `indices`, doubled with noisy copies if training_noise.
    IntegratorBatch make_batch(const TrainingSamples& samples, const std::vector<Index>& indices, Rng& rng) const;
    /// The same into `batch`, reusing its storage.
    void make_batch(const TrainingSamples& samples, const std::vector<Index>& indices, Rng& rng,
                    IntegratorBatch& batch) const;
    /// Loss of the batch; accumulates its parameter gradients into the model (the
    /// caller zeroes them). Network in training mode.
    double loss_and_gradient(LatentMlpModel& model, const IntegratorBatch& batch);
    /// Loss of the batch without gradients (same definition).
    double loss(LatentMlpModel& model, const IntegratorBatch& batch);

    /// Fit the input standardiser and output scale from the samples, then train.
    IntegratorTrainSummary train(LatentMlpModel& model, const TrainingSamples& samples);
    /// What train() does before its epochs: the input standardiser and output scale of
    /// `model`, the decoded-input cache and the balancing floor.
    void prepare(LatentMlpModel& model, const TrainingSamples& samples);
    /// The shared loop's options train() uses (labels, epochs, batches, seed, checkpoints).
    nn::TrainingLoopOptions loop_options() const;
    /// The learner train() hands to the shared loop (after prepare()); `model` and
    /// `samples` must outlive it. For nn::EpochRunner (the train_epoch benchmarks).
    std::unique_ptr<nn::Learner> learner(LatentMlpModel& model, const TrainingSamples& samples);
    /// p_t as options.boundary_input says, its pose relative to the physics' rest.
    BoundaryInput boundary_input() const { return BoundaryInput(m_options.boundary_input, m_model.spec()); }
    /// The velocity floor of data balancing (set by train() or set_velocity_floor()).
    double velocity_floor() const { return m_velocity_floor; }
    void set_velocity_floor(double v) { m_velocity_floor = v; }
    /// Mean |v_{t−1}| over the samples' ground-truth decoded inputs.
    double mean_input_speed(const TrainingSamples& samples);
    /// Data balancing's per-sample weights 1 / max(|v_{t−1}|, v_floor) of decoded inputs
    /// (3N × B each; |v_{t−1}| as options.balancing_velocity says).
    VectorXd balancing_weights(const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2) const;

    /// The resolved options as "key=value;..." text: every field that changes the numbers
    /// (fields that cannot matter, e.g. the noise fraction without noise, are left out;
    /// the penalty weight is the one applied, 0 for rods). Not progress/checkpointing.
    std::string resolved_options(Index num_samples) const;

    /// Decode the samples' ground-truth input latents once (x_{t−1}, x_{t−2} of the clean
    /// columns of every batch; the decoder is frozen, so they never change) and keep what
    /// the loss reads of them: x̃ = 2 x_{t−1} − x_{t−2} and |v_{t−1}|.
    void cache_decoded_inputs(const TrainingSamples& samples);

private:
    double evaluate(LatentMlpModel& model, const IntegratorBatch& batch, bool with_gradient);
    /// The batch columns' x̃ (3N × B) and, with data balancing, |v_{t−1}| (B): the clean
    /// columns from the cache, the noisy copies' input latents decoded.
    /// Into m_x_tilde and m_speeds.
    void step_inputs(const IntegratorBatch& batch);
    /// 1 / max(|v_{t−1}|, v_floor) of every speed.
    VectorXd weights_of(const Eigen::Ref<const VectorXd>& speeds) const;
    void weights_of(const Eigen::Ref<const VectorXd>& speeds, Eigen::Ref<VectorXd> weights) const;

    const PhysicsModel& m_model;
    Autoencoder& m_autoencoder;
    IntegratorTrainOptions m_options;
    LatentPotential m_potential;  ///< E(D(z)) with the applied w_bc (0 for rods: hard roots)
    double m_velocity_floor = 1e-6;
    MatrixXd m_cached_tilde;   ///< x̃ of every sample, 3N × S (empty: decode every batch)
    VectorXd m_cached_speeds;  ///< |v_{t−1}| of every sample (S)
    /// Batch workspaces that only grow: step_inputs' x̃ (3N × B) and speeds (B × 1), and the
    /// noisy columns' decoded x_{t−1}, x_{t−2}.
    nn::GrowingMatrix<double> m_x_tilde, m_speeds, m_x_prev, m_x_prev2;
    /// The supervised loss's Z − Z_target; either loss's adjoint ∂loss/∂Z; the samples'
    /// balancing weights.
    nn::GrowingMatrix<double> m_difference, m_latent_adjoint, m_weights;
};

} // namespace lb
