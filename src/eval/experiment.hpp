#pragma once
// Experiment suites: one TOML file describes scenes, dataset generation, the
// autoencoder, the integrators to compare, the evaluation protocol and the
// outputs (schema in README.md, "Experiment files"). `latentbench run` executes
//   simulate → train autoencoder → train integrators → roll out → tables → plots
// per scene, caching every stage: each output has a sidecar `<file>.key` holding
// a hash of the configuration that produced it (and of its inputs' keys); a
// re-run skips a stage whose key matches, `--force STAGE` redoes it.
#include <set>
#include <string>
#include <vector>

#include "baselines/linear_pca/linear_pca.hpp"
#include "integrators/trainer.hpp"
#include "latent/autoencoder.hpp"

namespace lb {

/// What an [[integrators]] entry builds: the latent MLP of Li et al. (trained with
/// `options`), or a baseline that needs no network.
enum class MethodKind { LatentMlp, LinearPca };

struct IntegratorSpec {
    std::string name;  ///< label in tables and file names
    MethodKind kind = MethodKind::LatentMlp;
    IntegratorTrainOptions options;  ///< latent MLP only
    bool hidden_given = false;  ///< else the paper's widths for the scene
    LinearPcaOptions linear_pca;   ///< linear_pca only; dim 0: the scene's latent size
};

struct SceneSpec {
    std::string scene_path;  ///< resolved
    std::string variant;
    std::string label;       ///< folder name and table label, e.g. "cloth_small"
    AutoencoderOptions autoencoder;
    bool latent_given = false;
    std::vector<IntegratorSpec> integrators;
};

struct AblationSpec {
    std::string name;
    std::string title;
    std::vector<std::string> methods;
};

struct ExperimentConfig {
    std::string name;
    std::string description;
    std::string source;      ///< file it came from
    std::string toml_text;   ///< resolved configuration, embedded in outputs
    std::string output_dir;  ///< run directory
    int threads = 0;
    std::vector<SceneSpec> scenes;
    // evaluation
    std::string sequences = "test";
    int rollout_frames = 0;
    bool full_space = true;
    // outputs
    bool plots = true;
    bool filmstrips = true;
    bool paper_tables = true;
    std::vector<AblationSpec> ablations;
};

/// Parse and validate; ConfigError naming the key on bad input.
ExperimentConfig load_experiment(const std::string& path);

/// Pipeline stages, in order (names accepted by --force).
const std::vector<std::string>& experiment_stages();

struct RunOptions {
    std::set<std::string> force;  ///< stage names, or "all"
    std::string output_dir;       ///< overrides the config's
};

struct RunResult {
    std::string run_dir;
    std::vector<std::string> tables;   ///< Markdown paths
    std::vector<std::string> figures;  ///< PNG paths
    int stages_run = 0;
    int stages_cached = 0;
    double seconds = 0.0;
};

RunResult run_experiment(const ExperimentConfig& config, const RunOptions& options);

} // namespace lb
