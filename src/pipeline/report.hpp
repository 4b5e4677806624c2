#pragma once
// Tables of a suite, rebuilt from the rollout files every run (cheap): one
// comparison per scene, one per ablation and scene, and the paper's Tables 1 and 2
// with our measurements beside the published figures.
#include <string>
#include <vector>

#include "eval/embedding_metrics.hpp"
#include "eval/metrics.hpp"
#include "nn/training_curve.hpp"
#include "pipeline/experiment.hpp"

namespace lb {

/// A learned method's training budget and how its training ended (artefact attributes).
struct TrainingBudget {
    bool recorded = false;  ///< false: the method records none (nothing trained)
    long long epochs_run = 0;
    long long epochs_budget = 0;  ///< 0: unknown
    double seconds = 0.0;
    double max_seconds = 0.0;  ///< 0: no wall-clock cap
    bool time_limited = false;
    bool stopped_early = false;
};

/// What the tables need of one method on one scene.
struct MethodResult {
    std::string name;     ///< label in tables
    std::string method;   ///< registered method name
    std::string summary;  ///< Method::summary()
    std::string layers;   ///< Method::layers()
    int fit_version = 0;  ///< Method::fit_version() (provenance)
    bool paper_method = false;
    std::string rollout_file;
    std::string rollout_key;  ///< the rollout stage's cache key (covers every input of the rollout)
    std::vector<RolloutSummary> summaries;  ///< one per evaluated sequence (and seed)
    /// Parallel to `summaries` (may be empty, e.g. in tests): each summary's sequence name
    /// and seed (-1: the method has no seed).
    std::vector<std::string> sequences;
    std::vector<long long> summary_seeds;
    /// With a suite's `seeds`: the seeds, and per seed the summary over its sequences.
    std::vector<std::uint64_t> seeds;
    std::vector<RolloutSummary> per_seed;
    std::vector<TrainingBudget> budgets;  ///< one per fit (per seed)
    /// Parallel to `budgets`: each fit's loss per epoch (empty: nothing trained, or an
    /// artefact written before curves were recorded). pipeline/training_curves.hpp.
    std::vector<nn::TrainingCurves> curves;
    /// The row whose fits this row rolls out when it has none of its own (an entry that
    /// differs from it only in `weights`): its curves are that row's, so the training
    /// table lists them once. "" for a row with its own fits.
    std::string fit_of;
    /// The sweep point of this row ("training.noise_fraction=0.05, seeds=1"); "" for a
    /// row shared by every point, or without a [sweep].
    std::string point;
    /// Embedding metrics a method measured in its fit (artefact attributes; the first seed's).
    std::vector<EmbeddingMetrics> embeddings;
};

struct SceneResult {
    std::string label;
    std::string dataset_file;
    std::string scene_name;
    Index dofs = 0;
    Index latent = 0;
    int train_frames = 0;
    /// Median Newton step recorded when the dataset was simulated (ms). That stage is
    /// cached, so this may come from another run, machine load or code version than
    /// the rollouts; Table 1's "simulation" column is the full_space rollout instead.
    double dataset_step_ms = 0.0;
    double jvp_ms = 0.0;         ///< one-vertex JVP through the decoder (float)
    std::string decoder_layers;
    /// The scene's autoencoder (of its first scene unit): its training curves and seed.
    nn::TrainingCurves autoencoder_curves;
    std::uint64_t autoencoder_seed = 0;
    /// What the suite's seeds vary: with SeedScope::autoencoder every seed has its own
    /// autoencoder (the curves and seed above are the first seed's).
    SeedScope seed_scope = SeedScope::integrator;
    std::vector<MethodResult> methods;
    /// Rows left out because a unit of a method with contained failures (method = "python")
    /// failed: "name: why", one per row; the methods table names them in a note.
    std::vector<std::string> failed_rows;
};

/// The tidy table of one scene (DESIGN rule: one row per observation): one row per method,
/// sweep point, seed, sequence and window, every summary metric by its field name (window
/// metrics of the row's window), flags `diverged` (stable_horizon < frames) and
/// `diverged_at` (the stable horizon, NaN if never). `seed` is NaN for a method without one,
/// `sweep point` "" without a [sweep] ("all points" for a row every point shares).
Table observations_table(const SceneResult& r);

/// Write every table (Markdown, CSV, LaTeX) into `dir`, and per scene the tidy
/// `rollouts_<label>.csv` (CSV only); returns the Markdown paths. A comparison table's CSV is
/// its machine-readable twin (summary_csv_columns: seed counts, divergence flags, median,
/// min and max per metric), not a copy of the Markdown cells. Every table carries the
/// suite's provenance note (suite_provenance_note).
std::vector<std::string> write_tables(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes,
                                      const std::string& dir);

/// "suite: NAME (FILE, fnv1a64 HASH); seeds: 0, 1, 2; fit versions: ours 3, ...; command: ..."
std::string suite_provenance_note(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes);

/// `provenance.json` of a run directory: the commit (and dirty flag) of the binary, the
/// suite file's name and content hash, the seeds, the thread count, every method's
/// fit_version, the command, machine and date. Written atomically.
void write_provenance(const ExperimentConfig& ex, const std::vector<SceneResult>& scenes, const std::string& run_dir);

/// The content hash of a suite file as provenance records it: "fnv1a64:<16 hex>" of its bytes.
std::string suite_file_hash(const std::string& path);

} // namespace lb
