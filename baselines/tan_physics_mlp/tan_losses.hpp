#pragma once
// The four losses of Tan, Pan, Gao & Manocha, "Realtime Simulation of Thin-Shell
// Deformable Materials using CNN-Based Mesh Embedding" (§IV, §VI-A), in position space:
// our autoencoder (E, D; BC-relative positions, no ACAP features) and the feature-space
// simulator z_m = MLP(z_{m−2}, z_{m−1}, q_m).
//
// q_m, the boundary control of frame m: the scene's boundary parameters of frames m,
// m−1, m−2 (p_m, p_{m−1}, p_{m−2}), exactly what the paper's integrator gets, so the MLP
// is a LatentMlpModel (integrators/latent_mlp_integrator.hpp: input [z_{m−1}, z_{m−2},
// p_m, p_{m−1}, p_{m−2}], output z_{m−1} + s ⊙ net(·)). Tan et al. give the grasp
// positions of frame m; our latents are relative to the Dirichlet mean already, so
// absolute Dirichlet targets would only tell the MLP where the cloth is (outside the
// training range in every test window), while the motion that drives the dynamics is
// the boundary's velocity over the three frames, which p carries. The Dirichlet targets
// are therefore not an input (README, "Baseline tan_physics_mlp").
//
// Losses (means over the batch; λ weights applied by the caller's options):
//   L_recon, L_ephys  latent/embedding_energy_loss.hpp (shared with the autoencoder's
//             physics_epochs option); L_recon is L_vert without ACAP features (the two terms
//             of Tan et al. coincide), L_ephys is Tan eq. 5 with their stop-gradient
//   L_sim   = Σ_b ‖MLP(z_{m−2}, z_{m−1}, q_m) − z_m‖² / B  on ground-truth latents z = E(x)
//   L_mphys = c_E Σ_b Σ_{k<K} E(D(ẑ_{m_k}); D(ẑ_{m_k−1}), D(ẑ_{m_k−2}), x*) / (B · K)
//             over windows of K steps unrolled from the ground-truth latents of two frames
//             (Tan eq. 8); with stop_gradient (their eq. 11) the partial derivatives of
//             each E with respect to its first two arguments are zero, while the chain
//             through the MLP's own inputs (back-propagation through time) is kept.
// E is the implicit-Euler incremental potential with the Dirichlet penalty
// (latent/latent_potential.hpp). c_E = 2h² / (3N m̄) puts it in the units of L_recon:
// the inertia term becomes the per-DOF mean squared distance (m²) to x̃ = 2x_{m−1} − x_{m−2}
// in units of the mean vertex mass, so Tan's λ values (1, 1, 0.1–1) weigh comparable
// numbers. Constant offsets (gravity potential) do not change gradients; a loss value may be
// negative.
//
// Stage 3 (Tan §VI-A): the decoder gets z′ = ½ z_m + ½ MLP(z_{m−2}, z_{m−1}, q_m), and
//   L_3 = λ_recon L_recon(z′) + λ_ephys L_ephys(z′) + λ_sim L_sim,
// every latent the encoder's (z_k = E(x_k)), gradients into E, D and the MLP.
//
// The autoencoder runs in eval mode throughout (BatchNorm with its running statistics,
// which are not updated; its affine weights train): the losses then see exactly the
// embedding that rollouts decode, and each sample's loss is independent of its batch.
#include <vector>

#include "integrators/latent_mlp_integrator.hpp"
#include "latent/embedding_energy_loss.hpp"

namespace lb {

using TanSequence = FrameSequence;
using TanSample = FrameSample;  ///< a frame m ≥ 2 (stages 1, 3) or the start t0 of a window (stage 2)

/// The parts of a loss (unweighted means; 0 for terms the loss does not have).
struct TanLossParts {
    double recon = 0.0, ephys = 0.0, sim = 0.0, mphys = 0.0;
};

struct TanWeights {
    double recon = 1.0, ephys = 0.5, sim = 1.0, mphys = 0.5;
};

class TanLosses {
public:
    /// @param model           physics (must outlive this object)
    /// @param data            its training frames are copied
    /// @param autoencoder     the embedding the losses train (must outlive this object)
    /// @param penalty_weight  w_bc of the incremental potential (0 for rods: applied_penalty_weight)
    TanLosses(const PhysicsModel& model, const Dataset& data, Autoencoder& autoencoder, double penalty_weight);

    const std::vector<TanSequence>& sequences() const { return m_embedding.sequences(); }
    /// Every frame m ≥ 2 of the training window of every sequence.
    std::vector<TanSample> frame_samples() const { return m_embedding.frame_samples(); }
    /// Every window start t0 with t0 + window + 1 < train_frames (frames t0 … t0+window+1).
    std::vector<TanSample> window_samples(Index window) const;
    /// The longest window every sequence can hold: min over sequences of train_frames − 2.
    Index max_window() const;
    /// c_E = 2h² / (3N m̄).
    double energy_scale() const { return m_embedding.energy_scale(); }
    Autoencoder& autoencoder() { return m_embedding.autoencoder(); }

    /// Stage 1: λ_recon L_recon + λ_ephys L_ephys over frames `batch` (EmbeddingEnergyLoss);
    /// with `gradient`, parameter gradients of the encoder and decoder are ACCUMULATED.
    double embedding_loss(const std::vector<TanSample>& batch, const TanWeights& w, bool gradient,
                          TanLossParts* parts = nullptr);
    /// Stage 2: λ_sim L_sim + λ_mphys L_mphys over windows `batch` of `window` steps; the
    /// autoencoder is frozen; with `gradient`, the MLP's parameter gradients are accumulated.
    /// stop_gradient = false differentiates Tan's eq. 8 as written (for tests and ablations).
    double mlp_loss(LatentMlpModel& mlp, const std::vector<TanSample>& batch, Index window, const TanWeights& w,
                    bool stop_gradient, bool gradient, TanLossParts* parts = nullptr);
    /// Stage 3: λ_recon L_recon(z′) + λ_ephys L_ephys(z′) + λ_sim L_sim over frames `batch`;
    /// gradients of encoder, decoder and MLP accumulated.
    double joint_loss(LatentMlpModel& mlp, const std::vector<TanSample>& batch, const TanWeights& w, bool gradient,
                      TanLossParts* parts = nullptr);

private:
    /// MLP inputs [z1, z2, p_m, p_{m−1}, p_{m−2}] for frames m of the batch.
    MatrixXd mlp_inputs(const MatrixXd& z1, const MatrixXd& z2, const std::vector<TanSample>& batch,
                        Index offset) const;

    EmbeddingEnergyLoss m_embedding;
};

} // namespace lb
