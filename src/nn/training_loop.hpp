#pragma once
// The one training loop of latentbench: every learned component (the autoencoder, the
// latent integrator, future learned baselines) supplies a Learner and gets epochs,
// seeded shuffles, mini-batches, Adam, optional validation with early stopping and
// best-weights restore, a time limit, progress lines and fingerprinted checkpoints.
//
// Per epoch e (0-based): the samples are shuffled (Fisher–Yates) with
// Rng(epoch_seed(seed, e)) and split into ceil(S / batch_size) batches of near-equal
// size (at most S / min_batch of them, so none is smaller than min_batch); the same Rng
// is then passed to every batch (noise). Seeding per epoch makes a resumed run draw
// exactly the batches and noise of an uninterrupted one. The epoch loss is the
// batch-size-weighted mean of the batch losses.
//
// Validation (if the learner has it): after every epoch; the best epoch's weights are
// snapshotted by the learner and restored at the end; with patience > 0, training stops
// after `patience` epochs without improvement.
//
// Checkpoints (nn/checkpoint.hpp): every checkpoint_every epochs and at the end (not
// after an interruption), written atomically. Contents: the fingerprint, the counters,
// parameters ("param/<name>"), Adam moments and step, the loss curve so far ("curve/":
// nn/training_curve.hpp; a resumed run continues it), plus the learner's extra state.
// At the start an existing checkpoint is resumed only if resume is on, its fingerprint
// matches and every tensor has the expected shape (checked before anything is copied);
// otherwise it is set aside as `<path>.stale.<n>` with a log line giving the reason and
// the name. A file that is not a checkpoint of this trainer (a dataset, an autoencoder,
// the checkpoint of another trainer) is refused with a ConfigError and left in place.
//
// SIGTERM or SIGINT during training (core/stop_signal.hpp; the CLI installs the handlers)
// stops the loop after the current epoch: it writes the checkpoint and throws Stopped, so
// a pre-empted or interrupted run loses no finished epoch.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "io/hdf5.hpp"
#include "nn/adam.hpp"
#include "nn/checkpoint.hpp"
#include "nn/layer.hpp"
#include "nn/training_curve.hpp"

namespace lb::nn {

class Learner {
public:
    virtual ~Learner() = default;
    /// Number of training samples S (shuffled and batched by the loop).
    virtual Index num_samples() const = 0;
    /// Trainable parameters (references stay valid during training); Adam updates them.
    virtual std::vector<ParameterRef> parameters() = 0;
    /// Loss of the samples `indices` in training mode, parameter gradients ACCUMULATED
    /// (the loop zeroes them before). `rng` is the epoch's stream (e.g. for noise).
    virtual double loss_and_gradient(const std::vector<Index>& indices, Rng& rng) = 0;

    /// Validation: if true, validation_loss() is called after every epoch (eval mode),
    /// and snapshot_best()/restore_best() keep the best epoch's weights.
    virtual bool has_validation() const { return false; }
    virtual double validation_loss() { return 0.0; }
    virtual void snapshot_best() { }
    virtual void restore_best() { }

    /// State besides parameters and optimiser (BatchNorm statistics, best weights).
    virtual void save_state(h5::File& /*file*/) { }
    /// Restore what save_state wrote, all or nothing: on a name or shape difference throw
    /// CheckpointMismatch (IoError if unreadable) before changing anything.
    virtual void load_state(const h5::File& /*file*/) { }
};

/// What every training run takes besides its hyper-parameters (the autoencoder's, the
/// integrator's and any learned method's options derive from it).
struct TrainingRunOptions {
    /// Stop after this many seconds of training (0: no limit), a resumed run's earlier
    /// processes included (as recorded in its checkpoint); the summary says so.
    double max_seconds = 0.0;
    /// Checkpoint file (empty: none), written every checkpoint_every epochs and at the end.
    /// It is resumed only if its fingerprint (resolved options and content hashes of the
    /// inputs, nn/checkpoint.hpp) matches; otherwise it is set aside as `<path>.stale.<n>`
    /// with a log line saying why.
    std::string checkpoint_path;
    int checkpoint_every = 100;
    /// false: never resume; an existing checkpoint is set aside (the pipeline's --force).
    bool resume = true;
    bool progress = true;
    /// Called after every epoch with the number of epochs completed; returning true stops
    /// training there as a killed run would stop: no further checkpoint is written (the
    /// best weights so far are still restored). For cancellation and tests; not fingerprinted.
    std::function<bool(int epochs_done)> interrupt;
};

struct TrainingLoopOptions : TrainingRunOptions {
    std::string label = "train";  ///< progress lines and messages
    /// What trains (e.g. "autoencoder", "latent integrator"), written into checkpoints: a
    /// checkpoint of another trainer is refused, never set aside (empty: the label).
    std::string trainer;
    int epochs = 100;
    Index batch_size = 256;
    Index min_batch = 1;          ///< 2 for training-mode BatchNorm
    /// false: ceil(S / batch_size) batches of near-equal size covering every sample;
    /// true: floor(S / batch_size) batches of exactly batch_size, the incomplete rest of
    /// each epoch's shuffle left out (one batch of all S if S < batch_size), so the Adam
    /// steps per epoch do not depend on the remainder.
    bool drop_last = false;
    double learning_rate = 1e-3;
    std::uint64_t seed = 0;
    int patience = 0;             ///< 0: no early stopping
};

struct TrainingLoopSummary {
    int epochs_run = 0;            ///< epochs completed in total (resumed ones included)
    int best_epoch = 0;            ///< with validation: the epoch whose weights were kept
    double best_validation = 0.0;
    double final_loss = 0.0;       ///< the last epoch's training loss
    /// Every epoch's training loss (and validation loss, if the learner has it), a resumed
    /// run's earlier epochs included (from its checkpoint; NaN if that checkpoint was written
    /// before curves were recorded). train_loss.back() == final_loss after ≥ 1 epoch. `stage`
    /// is the trainer's name; callers that store it name it (nn/training_curve.hpp).
    TrainingCurve curve;
    /// Wall-clock seconds of training, a resumed run's earlier processes included (their time is
    /// unknown, so left out, if the checkpoint was written before it was recorded).
    double seconds = 0.0;
    /// Of `seconds`, the earlier processes' (0 unless resumed): for callers that time more than the loop.
    double seconds_before = 0.0;
    bool resumed = false;
    bool stopped_early = false;
    bool time_limited = false;
    bool interrupted = false;
    std::string checkpoint_refused;
};

/// The RNG seed of epoch `epoch` (splitmix64 of the two).
std::uint64_t epoch_seed(std::uint64_t seed, int epoch);

/// The epochs of run_training_loop without its bookkeeping (checkpoints, validation,
/// progress): the learner's parameters, an Adam optimiser over them and the batch split.
/// run_training_loop runs its epochs through this class; benchmarks (train_epoch/<scene>)
/// time exactly that code.
class EpochRunner {
public:
    /// Throws ConfigError naming options.label on bad options (epochs < 0, batch below
    /// min_batch, non-positive learning rate, too few samples).
    EpochRunner(Learner& learner, const TrainingLoopOptions& options);
    /// Epoch `epoch` (0-based): shuffle with Rng(epoch_seed(seed, epoch)), one Adam step
    /// per batch. Returns the sample-weighted mean batch loss.
    double run(int epoch);
    std::vector<ParameterRef>& parameters() { return m_params; }
    Adam& adam() { return m_adam; }
    /// Batches per epoch and the samples they cover (all S unless drop_last).
    Index num_batches() const { return Index(m_bounds.size()) - 1; }
    Index samples_per_epoch() const { return m_bounds.back(); }

private:
    Learner& m_learner;
    std::uint64_t m_seed;
    std::vector<ParameterRef> m_params;
    Adam m_adam;
    std::vector<Index> m_bounds;
    std::vector<Index> m_order;
    std::vector<Index> m_batch;  ///< the current batch's sample indices (kept: no allocation per epoch)
};

/// A training checkpoint's account of its run's progress (`latentbench status`).
struct CheckpointProgress {
    std::string trainer;  ///< e.g. "autoencoder", "latent integrator" ("" if not recorded)
    int epoch = 0;        ///< epochs completed
    int epochs = 0;       ///< the budget, from the fingerprint's options ("epochs="; 0 if absent)
    double seconds = -1;  ///< wall-clock training seconds so far, earlier processes included (< 0: not recorded)
};

/// The progress recorded in the checkpoint `path` (its attributes only; nothing is
/// resumed or changed); nullopt if there is no file or it is not a readable training
/// checkpoint.
std::optional<CheckpointProgress> read_checkpoint_progress(const std::string& path);

/// Train `learner`; `fingerprint` identifies everything the numbers depend on (nn/checkpoint.hpp).
/// Throws NumericalError if the loss becomes non-finite.
TrainingLoopSummary run_training_loop(Learner& learner, const TrainingLoopOptions& options,
                                      const Fingerprint& fingerprint);

} // namespace lb::nn
