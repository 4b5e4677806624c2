#pragma once
// A suite as independent work units, for `latentbench plan`, `run --unit`, `run
// --merge` and `submit` (README, "Running on a cluster"):
//   scene  one scene's full-space dataset and autoencoder (stages simulate, autoencoder)
//   fit    one method × seed × sweep point fitted on it (stage integrators)
//   eval   its rollouts with every metric (stage rollouts)
// Each unit's outputs carry the stage cache's keys (stage_cache.hpp), computed here
// from the configuration alone, so a unit is complete when its files exist with these
// keys, whichever machine ran it. Units whose configuration is the same for every
// sweep point (the dataset, full_space, a method the sweep does not touch) are planned
// once and shared by the points.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "latent/autoencoder.hpp"
#include "pipeline/experiment.hpp"

namespace lb {

struct Scene;

enum class UnitKind { Scene, Fit, Eval };
const char* unit_kind_name(UnitKind kind);

/// A stage output and the cache key that makes it current.
struct UnitOutput {
    std::string file;  ///< absolute path under the run directory
    std::string key;
};

struct Unit {
    std::string id;  ///< "scene.<label>", "fit.<label>.<stem>", "eval.<label>.<stem>"
    UnitKind kind = UnitKind::Scene;
    int level = 0;        ///< 0 scene, 1 fit (or eval of a method with nothing to fit), 2 eval
    int array_index = 0;  ///< position among the units of its level (the Slurm array index)
    std::string scene;    ///< scene label
    std::string method;   ///< integrator name ("" for a scene unit)
    std::string stem;     ///< file stem: <method>[.<point>][.seed<k>]
    std::optional<std::uint64_t> seed;
    std::string point;       ///< sweep point label, "" if shared by every point (or no sweep)
    std::string point_text;  ///< "training.noise_fraction=0.05, seeds=1"
    std::vector<std::string> depends_on;
    std::vector<UnitOutput> outputs;
    // where its configuration comes from
    size_t point_index = 0;         ///< into experiment_points()
    size_t scene_index = 0;         ///< into the point's scenes
    size_t method_index = 0;        ///< into the scene's methods (fit, eval)
    bool full_space = false;        ///< the built-in reference (eval only)
    std::string scene_dir;          ///< run_dir/<label>[.<point>]
    std::string scene_unit;         ///< the scene unit whose dataset and autoencoder it uses
    std::string fit_unit;           ///< eval: the fit unit of its artefact ("" if none)
};

/// One table row: a method on a scene at a sweep point (or every point), over its seeds.
struct PlannedRow {
    size_t scene_index = 0;
    std::string name;
    std::string point_text;               ///< "" for a row shared by every point
    std::vector<std::string> eval_units;  ///< one per seed
    std::vector<std::uint64_t> seeds;     ///< empty: the method takes no seed
};

struct ExperimentPlan {
    std::string suite;    ///< the suite file
    std::string run_dir;  ///< absolute
    std::vector<Unit> units;           ///< in dependency order (levels ascending)
    std::vector<PlannedRow> rows;      ///< per scene, in table order
    std::vector<std::string> scene_units;  ///< per scene of the suite: the unit giving its table facts
    size_t points = 1;                 ///< sweep points (1 without a sweep)

    int levels() const;
    /// nullptr if no unit has this id
    const Unit* find(const std::string& id) const;
};

/// Every unit of a suite; loads each scene (cheap) to compute the keys; runs nothing.
ExperimentPlan plan_experiment(const ExperimentConfig& ex, const std::string& run_dir);

/// The run directory: `output_dir` (or the suite's) made absolute.
std::string resolve_run_dir(const ExperimentConfig& ex, const std::string& output_dir);

/// The built-in reference simulator `full_space` that every suite may roll out.
std::unique_ptr<Method> reference_method();

/// The manifest: one JSON object per line and unit (README, "Running on a cluster").
std::string manifest_jsonl(const ExperimentConfig& ex, const ExperimentPlan& plan);

/// `<run_dir>/units/<id>.status`, where a unit records how its last run went
/// (run_experiment.cpp writes it; `latentbench status` and the merge read it).
std::string unit_status_path(const std::string& run_dir, const std::string& id);
/// A status file as written: its status ("running", "done", "failed" or "stopped"), where
/// and when ("<host> pid <pid> <date>"), and its details joined on one line.
struct UnitStatusRecord {
    std::string status, where, detail;
};
/// The status file at `path`, or nullopt if it is missing or empty. A signal's stop that
/// a run before "stopped" existed recorded as "failed" (the training loop's "... stopped
/// by SIGTERM after epoch ...; the next run resumes from it") reads as "stopped".
std::optional<UnitStatusRecord> read_status_file(const std::string& path);
/// read_status_file(unit_status_path(run_dir, id)).
std::optional<UnitStatusRecord> read_unit_status(const std::string& run_dir, const std::string& id);
/// The training checkpoint a unit writes while it trains: a scene unit's autoencoder
/// (`<scene_dir>/ae.checkpoint.h5`), a fit unit's method
/// (`<scene_dir>/integrators/<stem>.checkpoint.h5`); "" for an eval unit.
std::string unit_checkpoint_path(const Unit& unit);

/// True if every output of `unit` exists with its key.
bool unit_complete(const Unit& unit);
/// True if `output` exists with its key (its `.key` sidecar).
bool unit_output_current(const UnitOutput& output);

// ---- cache keys, shared by the planner and the stages (run_experiment.cpp) ----------
/// The autoencoder options a scene trains with (latent default per scene filled in); `seed`:
/// a scene unit's own seed under `[seeds] scope = "autoencoder"` (Unit::seed), which replaces
/// the [autoencoder] seed.
AutoencoderOptions resolved_autoencoder(const SceneSpec& spec, const Scene& scene,
                                        std::optional<std::uint64_t> seed = std::nullopt);
std::string simulate_key(const Scene& scene);
std::string autoencoder_stage_key(const std::string& sim_key, const AutoencoderOptions& options);
/// A method's artefact key (the method resolved and its seed set).
std::string method_stage_key(const Method& method, const std::string& sim_key, const std::string& ae_key);
std::string rollout_stage_key(const std::string& method_key, const ExperimentConfig& ex,
                              nn::WeightFormat weights = nn::WeightFormat::f32);

} // namespace lb
