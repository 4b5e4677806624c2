#pragma once
// The autoencoder of Li et al. 2025 §3.2 / DESIGN §4: an MLP-ResNet with
// BatchNorm and Swish, encoder and decoder symmetric; the encoder's first layer
// and the decoder's last layer are linear layers of width d_pca initialised from
// a PCA of the training frames (basis and mean), then trained with the
// full-space reconstruction MSE. Positions are BC-relative (bc_encoding.hpp).
//
// File format (HDF5): encoder.* and decoder.* state_dict-style datasets
// (nn/serialization.hpp, with the encoder.architecture / decoder.architecture JSON
// attributes) plus root attributes:
//   format "latentbench.autoencoder/1", latent_dim, pca_dim (after clamping),
//   hidden ("200,200,200", decoder order), batch_norm, residual (0/1),
//   encoding ("rod_root" | "dirichlet_mean"), num_features F, num_dofs 3N,
//   scene (dataset scene name), seed; if saved with its training curves (train_autoencoder's
//   summary), training_curve/* (nn/training_curve.hpp) and final_loss, the last stage's last
//   epoch loss (files written before curves were recorded have neither).
// The decoder maps z to features f; positions are x = P f + offset(bc targets)
// (bc_encoding.hpp), so scripts/nn_reference.py --prefix decoder. gives f.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/rng.hpp"
#include "latent/bc_encoding.hpp"
#include "nn/sequential.hpp"
#include "nn/training_loop.hpp"
#include "sim/dataset.hpp"

namespace lb {

namespace h5 {
class File;
}

/// Which frames the autoencoder trains on (issue 39; the paper does not say): the training
/// window only (frames before each sequence's train_frames, the default) or every frame,
/// the test window included. The integrators train on the training window either way.
enum class AutoencoderFrames { train, all };
std::string to_string(AutoencoderFrames frames);
/// "train" / "all"; throws ConfigError naming the accepted values.
AutoencoderFrames autoencoder_frames_from_string(const std::string& text);

struct AutoencoderOptions : nn::TrainingRunOptions {
    // architecture
    Index latent_dim = 4;
    std::vector<Index> hidden{200, 200, 200};  ///< decoder widths after the latent; encoder mirrors them
    Index pca_dim = 50;                        ///< clamped to the training features' numerical rank
    bool batch_norm = true;
    bool residual = true;
    /// The features' frame (bc_encoding.hpp): the paper's translation-only one, or the
    /// boundary's rigid frame (rotation removed as well).
    EncodingFrame frame = EncodingFrame::translation;
    AutoencoderFrames frames_seen = AutoencoderFrames::train;  ///< suite key `autoencoder_frames`
    // training (Adam, lr 1e-4, batch 500 in the paper)
    int epochs = 2000;
    int batch_size = 500;
    double learning_rate = 1e-4;
    /// Every k-th training frame goes to validation (k = round(1/validation_fraction)).
    double validation_fraction = 0.1;
    /// Early stopping: stop after this many epochs without a validation improvement (0: never).
    int patience = 200;
    std::uint64_t seed = 0;
    // Physics fine-tuning (embedding_energy_loss.hpp; Tan et al.'s L_ephys): after the
    // reconstruction training, physics_epochs epochs of L_recon + physics_weight · L_ephys
    // over the training frames m ≥ 2 (0: none, the paper's autoencoder).
    int physics_epochs = 0;
    double physics_weight = 0.5;          ///< λ_ephys (Tan et al.'s 0.5; λ_recon is 1)
    double physics_learning_rate = 1e-5;  ///< Tan et al.'s fine-tuning rate (stages 1, 3)
    int physics_batch = 64;               ///< frames per batch
    double physics_penalty_weight = 1e5;  ///< w_bc of the potential (0 applied for rods)
};

/// The shared loop's summary (best_validation: mean squared error per DOF (m²) of the
/// kept weights; final_loss: the last epoch's training-mode loss) plus the error in metres.
struct AutoencoderTrainSummary : nn::TrainingLoopSummary {
    /// Relative RMS reconstruction error on validation frames: RMS(x̂ − x) / bbox diagonal,
    /// of the returned autoencoder. After a physics fine-tuning the validation frames are
    /// not held out from it (it trains on every training frame m ≥ 2, as Tan et al.'s
    /// stage 1): validation_relative_rmse_held_out is the value before it.
    double validation_relative_rmse = 0.0;
    double validation_relative_rmse_held_out = 0.0;
    /// Physics fine-tuning (options.physics_epochs > 0): L_recon and L_ephys (unweighted
    /// means over the training frames m ≥ 2) before and after, its epochs and seconds.
    bool physics_ran = false;
    double physics_recon_before = 0.0, physics_recon_after = 0.0;
    double physics_ephys_before = 0.0, physics_ephys_after = 0.0;
    int physics_epochs_run = 0;
    double physics_seconds = 0.0;
    /// The loss per epoch of each training run, in order: "autoencoder" (reconstruction MSE,
    /// with validation) and, after a physics fine-tuning, "physics" (its training loss).
    nn::TrainingCurves curves;
};

class Autoencoder {
public:
    /// Builds encoder and decoder (PyTorch-default initialised from `seed`); pca_dim is
    /// clamped to the number of features here and to S − 1 by initialize_pca.
    /// pca_dim = 0 builds plain MLPs without PCA layers. Throws ConfigError on bad options.
    Autoencoder(const PhysicsSpec& physics, const AutoencoderOptions& options, std::uint64_t seed);

    Index latent_dim() const { return m_options.latent_dim; }
    Index num_features() const { return m_encoding.num_features(); }
    const AutoencoderOptions& options() const { return m_options; }
    const BcRelativeEncoding& encoding() const { return m_encoding; }
    nn::Sequential& encoder() { return m_encoder; }
    nn::Sequential& decoder() { return m_decoder; }
    std::uint64_t seed() const { return m_seed; }
    /// Rest bounding-box diagonal (m): the length scale of relative errors.
    double length_scale() const { return m_length_scale; }
    /// Scene the autoencoder was trained on (set by train_autoencoder, saved, loaded).
    const std::string& scene_name() const { return m_scene_name; }
    void set_scene_name(std::string name) { m_scene_name = std::move(name); }

    /// Set the encoder's first and the decoder's last linear layer from a PCA of the
    /// training features (F × S): W_enc = U_dᵀ, b_enc = −U_dᵀ μ, W_dec = U_d, b_dec = μ.
    /// If min(pca_dim, S − 1, the features' numerical rank) is below the current width,
    /// pca_dim is lowered to it (recorded in options(); a warning states both numbers when
    /// the rank decides) and both networks are rebuilt from seed() first.
    /// Returns the fraction of the features' variance the d directions capture.
    double initialize_pca(const MatrixXd& features);

    // Evaluation mode (BatchNorm running statistics); columns are frames.
    /// 3N × S positions → latent × S.
    MatrixXd encode(const MatrixXd& X);
    /// The codes of two states (an integrator's two initial frames), encoded as one batch.
    std::pair<VectorXd, VectorXd> encode_pair(const VectorXd& first, const VectorXd& second);
    /// latent × S → F × S features.
    MatrixXd decode_features(const MatrixXd& Z);
    /// latent × S and 3B × S Dirichlet targets → 3N × S positions.
    MatrixXd decode(const MatrixXd& Z, const MatrixXd& bc_targets);
    /// Per column s: J_D(z_s)ᵀ ∂L/∂x_s, the gradient w.r.t. the latent of a loss of the
    /// decoded positions (one vector-Jacobian product through the frozen decoder).
    /// @param Z  latent × S, @param grad_x  3N × S, @param bc_targets  3B × S (the
    /// targets the positions were decoded with) @return latent × S
    MatrixXd decoder_vjp(const MatrixXd& Z, const MatrixXd& grad_x, const MatrixXd& bc_targets);
    /// decode(encode(X)) in eval mode, compared with X: RMS over vertices and frames of
    /// |x̂_i − x_i| (Euclidean per vertex), divided by length_scale().
    /// @param X  3N × S  @param bc_targets  3B × S
    double relative_rmse(const MatrixXd& X, const MatrixXd& bc_targets);

    /// FNV-1a/64 (16 hex digits) of everything that defines encode/decode: encoding kind,
    /// Dirichlet set, feature count, latent size and both networks' parameters and buffers.
    /// Identifies this autoencoder in the fingerprints of checkpoints trained on it.
    std::string content_hash();

    /// Written atomically (temporary file, then rename). See the file format above.
    /// `curves` (train_autoencoder's summary): stored with nn::save_training_curves, and
    /// the attribute final_loss = the last stage's last training loss.
    void save(const std::string& path, const nn::TrainingCurves& curves = {});
    /// Throws IoError naming the file if it is not an autoencoder file or its feature
    /// count / encoding kind does not match `physics`.
    static Autoencoder load(const std::string& path, const PhysicsSpec& physics);
    /// The same layout inside an open file, every dataset and attribute name prefixed with
    /// `prefix` (e.g. "tan_ae."): a method's artefact that carries its own autoencoder.
    void save_into(h5::File& file, const std::string& prefix);
    static Autoencoder load_from(const h5::File& file, const std::string& prefix, const PhysicsSpec& physics);

private:
    struct NoNetworks { };
    Autoencoder(const PhysicsSpec& physics, const AutoencoderOptions& options, std::uint64_t seed, NoNetworks);
    void build_networks();

    AutoencoderOptions m_options;
    BcRelativeEncoding m_encoding;
    nn::Sequential m_encoder;
    nn::Sequential m_decoder;
    std::uint64_t m_seed = 0;
    double m_length_scale = 1.0;
    std::string m_scene_name;
};

/// Training frames of a dataset as columns: positions (3N × S) and Dirichlet
/// targets (3B × S), from frames [0, train_frames) of every sequence.
struct FrameSet {
    MatrixXd positions;
    MatrixXd bc_targets;
};
FrameSet training_frames(const Dataset& data, AutoencoderFrames which = AutoencoderFrames::train);

/// Train with the reconstruction MSE; PCA-initialises first. Progress (epoch,
/// train/validation loss, time) on stderr; checkpoints and resume as in the options.
///
/// Details:
/// - The architecture is ae's; only the training fields of `options` are used
///   (epochs, batch_size, learning_rate, validation_fraction, patience, seed,
///   checkpoint_path, checkpoint_every, progress).
/// - Split: training frames (training_frames(data)) in order; frame j goes to validation
///   iff j % k == k − 1, k = max(2, round(1/validation_fraction)); validation_fraction ≤ 0
///   means no validation (the training frames are then evaluated in eval mode instead).
///   PCA is fitted on the remaining (training) frames only.
/// - Loss: mean squared error per position DOF, computed on the features:
///   ||f̂ − f||² / (3N · batch). For ground-truth frames the BC offset is exact, so this
///   equals the position MSE (rods: the roots' error is identically zero).
/// - The epochs run in the shared loop (nn/training_loop.hpp): epoch e shuffles the
///   training frames with Rng(epoch_seed(options.seed, e)) (Fisher–Yates) and splits them
///   into min(ceil(S/batch_size), S/2) batches of near-equal size (so none has fewer than
///   the 2 frames training-mode BatchNorm needs).
///   BatchNorm runs in training mode for the updates, eval mode for validation.
/// - Early stopping: after `patience` epochs without a validation improvement; the
///   best-validation weights are restored at the end either way.
/// - Checkpoint (if checkpoint_path is set): every checkpoint_every epochs and at the end,
///   written atomically; holds weights, BatchNorm statistics, the best weights, Adam state,
///   epoch counters (no RNG state: shuffles are seeded per epoch). If the file exists at the start, resume
///   is on and its fingerprint matches (nn/checkpoint.hpp: resolved options, i.e.
///   architecture, init seed, epochs, batches, lr, validation split, patience, seed; a hash
///   of the training features; a hash of the PCA-initialised starting networks), training
///   resumes from it bit-for-bit. Otherwise (or if any tensor has the wrong shape) it is
///   set aside as `<path>.stale` with a log line saying why, and training starts afresh.
/// - Same seed and data → bitwise-identical weights (single-threaded Eigen).
/// - Physics fine-tuning (options.physics_epochs > 0), after the above: the shared loop on
///   L_recon + physics_weight · L_ephys (EmbeddingEnergyLoss) over every training frame
///   m ≥ 2, eval-mode BatchNorm, Adam at physics_learning_rate, no validation or early stop;
///   checkpoint `<checkpoint_path>.physics` (fingerprint: these options, the trained
///   autoencoder's content hash, the data and the physics). validation_relative_rmse is
///   measured after it.
AutoencoderTrainSummary train_autoencoder(Autoencoder& ae, const Dataset& data, const AutoencoderOptions& options);


} // namespace lb
