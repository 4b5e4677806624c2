#pragma once
// Experiment suites: one TOML file describes scenes, dataset generation, the
// autoencoder, the methods to compare, the evaluation protocol and the outputs
// (schema in README.md, "Experiment files"). `latentbench run` executes
//   simulate → train autoencoder → fit methods → roll out → tables → plots
// per scene, caching every stage (pipeline/stage_cache.hpp).
//
// The pipeline in pieces:
//   experiment.hpp / experiment_config.cpp   the configuration and its parser ([sweep] too)
//   plan.hpp                                  the suite as independent work units (manifest)
//   stage_cache.hpp                           keys, --force, stale checkpoints
//   run_experiment.cpp                        one unit's stages; merge; the local run
//   slurm.hpp                                 sbatch scripts per dependency level
//   report.hpp                                tables from the rollout files
//   plots.hpp                                 figures and videos (Python scripts, posix_spawn)
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "latent/autoencoder.hpp"
#include "methods/registry.hpp"
#include "nn/weight_format.hpp"

namespace lb {

/// One [[integrators]] entry on one scene.
struct MethodSpec {
    std::string name;                ///< label in tables and file names
    std::shared_ptr<Method> method;  ///< parsed options (resolved when the scene is known)
    /// The entry's own `seeds = [...]`: a subset of the suite's seeds that this method runs
    /// (e.g. one seed of an expensive baseline); empty: every seed of the suite.
    std::vector<std::uint64_t> seeds;
    /// The entry's `weights`: what its rollouts' float inference networks stream (f32, f16,
    /// int8; methods whose uses_weight_format() is true). Not a fit option: an entry that
    /// differs from another only in `weights` rolls out that entry's artefact, not a new fit.
    nn::WeightFormat weights = nn::WeightFormat::f32;
};

/// What the suite's seeds vary (ExperimentConfig::seed_scope).
enum class SeedScope { integrator, autoencoder };
const char* seed_scope_name(SeedScope scope);

struct SceneSpec {
    std::string scene_path;  ///< resolved
    std::string variant;
    std::string label;       ///< folder name and table label, e.g. "cloth_small"
    AutoencoderOptions autoencoder;
    bool latent_given = false;
    bool hidden_given = false;  ///< the suite or scene set [autoencoder] hidden
    /// The suite's `recipe` ("paper" or "none"): with "paper", an autoencoder whose widths are
    /// not set gets Table 2's decoder widths for the scene (resolved_autoencoder).
    std::string recipe = "none";
    std::vector<MethodSpec> methods;
};

struct AblationSpec {
    std::string name;
    std::string title;
    std::vector<std::string> methods;
};

/// One axis of a `[sweep]` table: a dotted key and the values it takes.
struct SweepAxis {
    std::string key;                  ///< "training.noise_fraction", "autoencoder.epochs" or "seeds"
    std::vector<std::string> values;  ///< each value as TOML text, e.g. "0.05", "[32, 32]"
};

/// At most this many points in a [sweep] (the product of the axes' lengths).
inline constexpr size_t kMaxSweepPoints = 1000;

struct ExperimentConfig {
    std::string name;
    std::string description;
    std::string source;      ///< file it came from
    std::string toml_text;   ///< resolved configuration, embedded in outputs
    std::string output_dir;  ///< run directory
    int threads = 0;
    /// `recipe = "paper"`: every [autoencoder] and [training] key the suite does not set takes
    /// the paper's stated value (paper/paper_recipe.hpp); "none" (default): latentbench's defaults.
    std::string recipe = "none";
    /// `seeds = [...]`: every method whose fit depends on a seed (Method::set_seed) is
    /// fitted and rolled out once per seed, and the tables give statistics over the
    /// seeds. Empty: once, with the method's own seed.
    std::vector<std::uint64_t> seeds;
    /// What a seed varies (`[seeds] scope`): "integrator" (default) seeds each fitted method's
    /// initialisation and training order over one autoencoder per scene; "autoencoder" also
    /// trains one autoencoder per seed (its seed the suite's seed), and every method that uses
    /// the autoencoder is fitted once per seed on that seed's autoencoder.
    SeedScope seed_scope = SeedScope::integrator;
    std::vector<SceneSpec> scenes;
    // evaluation
    std::string sequences = "test";
    int rollout_frames = 0;
    bool full_space = true;
    // outputs
    bool plots = true;
    bool filmstrips = true;
    bool paper_tables = true;
    /// One side-by-side MP4 per scene (scripts/plot_video.py; needs Debian's ffmpeg).
    bool videos = false;
    /// Longest video in frames (30 fps): longer sequences are subsampled.
    int video_frames = 450;
    /// `latentbench diagnose` per scene (tables/diagnose_<scene>.*): the error decomposition
    /// of every latent method's first seed on the evaluated sequences, every
    /// `diagnose_stride`-th frame.
    bool diagnose = false;
    int diagnose_stride = 10;
    std::vector<AblationSpec> ablations;
    /// `[sweep]`: the axes, in key order; their cartesian product is `points`. Empty: no sweep.
    std::vector<SweepAxis> sweep;
    /// One resolved configuration per sweep point (the first axis varies slowest); each
    /// is this configuration with the point's values set and no [sweep]. Empty without one.
    std::vector<ExperimentConfig> points;
    std::string point_label;  ///< of a point: "p00", "p01", ... (a file-name part); "" otherwise
    std::string point_text;   ///< of a point: "training.noise_fraction=0.05, seeds=1"
    std::vector<std::string> point_values;  ///< of a point: its value (TOML text) per axis of `sweep`
};

/// Parse and validate; ConfigError naming the key on bad input. Each [[integrators]]
/// entry is parsed by the method its `method` key names (default "latent_mlp"). Every
/// point of a [sweep] is expanded and validated too (errors name the sweep key).
ExperimentConfig load_experiment(const std::string& path, const MethodRegistry& registry);

/// A subset of a suite: only the scenes labelled `scenes` and the [[integrators]] entries
/// named `integrators` (empty: all of either). Units keep their keys and file names, so a
/// subset run in the suite's run directory shares its cache with the whole suite (e.g. the
/// paper's method and its supervised baseline first, the rest later). Ablations that lose a
/// method are left out; the resolved TOML text gains a comment naming the subset.
/// ConfigError naming an unknown label or name, or a scene left with no method.
ExperimentConfig select_subset(const ExperimentConfig& ex, const std::vector<std::string>& scenes,
                               const std::vector<std::string>& integrators);

/// The configurations a suite runs: its sweep points, or the suite itself without [sweep].
std::vector<const ExperimentConfig*> experiment_points(const ExperimentConfig& ex);

/// Pipeline stages, in order (names accepted by --force).
const std::vector<std::string>& experiment_stages();

struct RunOptions {
    std::set<std::string> force;  ///< stage names, or "all"
    std::string output_dir;       ///< overrides the config's
    /// Other run directories (`run --reuse DIR`): a unit output whose cache key equals that
    /// of a file there (its `.key` sidecar) is copied instead of recomputed, e.g. the
    /// dataset and autoencoder that several suites of one scene share. Never for a forced
    /// stage; a copy that does not open is recomputed as any damaged cache entry is.
    std::vector<std::string> reuse;
};

struct RunResult {
    std::string run_dir;
    std::vector<std::string> tables;   ///< Markdown paths
    std::vector<std::string> figures;  ///< PNG paths
    std::vector<std::string> videos;   ///< MP4 paths (one per scene with `[outputs] videos`)
    int stages_run = 0;
    int stages_cached = 0;
    double seconds = 0.0;
    /// Units of methods with contained failures (method = "python") that failed, "id: why";
    /// run and merge write the other rows' tables, then throw an Error naming these.
    std::vector<std::string> failed_units;
};

/// The local run: every work unit of the suite in order (pipeline/plan.hpp), then the
/// merge. Stages whose outputs are current are skipped (stage_cache.hpp).
RunResult run_experiment(const ExperimentConfig& config, const RunOptions& options);

/// `run --unit ID`: one work unit, after checking that the units it depends on have
/// completed; idempotent (a completed unit does no work) and resumable (training resumes
/// from its checkpoint). Its log is `<run_dir>/units/<ID>.log`, its state
/// `<run_dir>/units/<ID>.status`. ConfigError for an unknown id.
RunResult run_unit(const ExperimentConfig& config, const std::string& id, const RunOptions& options);

/// `run --merge`: tables, figures and videos from the units' outputs. Error naming every
/// unit that has not completed (and why: not run, failed, killed) before writing anything.
RunResult merge_units(const ExperimentConfig& config, const RunOptions& options);

} // namespace lb
