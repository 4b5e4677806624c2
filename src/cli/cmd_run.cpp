#include <cstdio>
#include <filesystem>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "pipeline/deviations.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "scene/scene.hpp"

namespace lb::cli {
namespace {

/// `run --check`: every scene loaded and validated, then what would run.
void print_plan(const ExperimentConfig& ex, const std::string& run_dir, const std::string& deviations_dir)
{
    std::printf("experiment %s: %zu scenes, run directory %s\n", ex.name.c_str(), ex.scenes.size(), run_dir.c_str());
    for (const SceneSpec& s : ex.scenes) {
        const Scene scene = load_scene(s.scene_path, {s.variant});
        long frames = 0;
        for (const SequenceSpec& q : scene.sequences) frames += q.frames;
        const AutoencoderOptions ao = resolved_autoencoder(s, scene);  // the per-scene latent default filled in
        std::printf("  %s: %s, %ld vertices, %zu sequences, %ld frames; autoencoder latent %ld, %d epochs\n",
                    s.label.c_str(), s.scene_path.c_str(), long(scene.mesh.num_vertices()), scene.sequences.size(),
                    frames, long(ao.latent_dim), ao.epochs);
        for (const MethodSpec& m : s.methods)
            std::printf("    %-20s %s\n", m.name.c_str(), m.method->method_name().c_str());
    }
    std::printf("evaluation: sequences %s, frames %s, full_space %s\n", ex.sequences.c_str(),
                ex.rollout_frames > 0 ? std::to_string(ex.rollout_frames).c_str() : "all",
                ex.full_space ? "yes" : "no");
    print_unit_plan(ex, plan_experiment(ex, resolve_run_dir(ex, run_dir)), false);
    for (const SceneSpec& s : ex.scenes) {
        const Scene scene = load_scene(s.scene_path, {s.variant});
        const Table deviations = deviations_table(ex, s, scene.name, resolved_autoencoder(s, scene));
        std::printf("\n%s", to_markdown(deviations).c_str());
        if (!deviations_dir.empty()) {
            const std::vector<std::string> written =
                write_table_files(deviations, deviations_dir + "/deviations_" + s.label);
            std::printf("written: %s\n", written.front().c_str());
        }
    }
    std::printf("the configuration is valid; nothing was run\n");
}

} // namespace

void register_run(CLI::App& app)
{
    struct Args {
        std::string experiment, output;
        std::vector<std::string> force;
        std::string unit;
        bool check = false, merge = false;
        std::string deviations_dir;
        std::vector<std::string> scenes, integrators, reuse;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("run", "Run an experiment suite: simulate, train, roll out, tables, plots (cached stages)");
    cmd->add_option("experiment", a->experiment, "Experiment TOML (experiments/*.toml)")->required();
    cmd->add_option("-o,--output", a->output, "Run directory (default: the experiment's output_dir)");
    cmd->add_option("--force", a->force,
                    "Redo a stage even if cached: simulate, autoencoder, integrators, rollouts, tables, plots, all");
    CLI::Option* check = cmd->add_flag("--check", a->check, "Validate the suite and its scenes, print the plan and run nothing");
    CLI::Option* unit = cmd->add_option("--unit", a->unit, "Run one work unit (ids: `latentbench plan`); idempotent");
    CLI::Option* merge = cmd->add_flag("--merge", a->merge,
                                       "Tables, figures and report from the work units' outputs; names every unit missing");
    cmd->add_option("--scene", a->scenes,
                    "Run only the scene with this label (repeatable); tables cover the subset, the cache is shared "
                    "with the whole suite");
    cmd->add_option("--integrator", a->integrators,
                    "Run only the [[integrators]] entry with this name (repeatable; full_space runs as configured)");
    cmd->add_option("--reuse", a->reuse,
                    "Another suite's run directory (repeatable): outputs with the same cache key there (a "
                    "scene's dataset and autoencoder, fits, rollouts) are copied instead of recomputed");
    cmd->add_option("--write-deviations", a->deviations_dir,
                    "With --check: also write each scene's deviations table (deviations_<scene>.md/.csv/.tex) into "
                    "this existing folder, e.g. a published suite's tables/")
        ->check(CLI::ExistingDirectory)
        ->needs(check);
    check->excludes(unit)->excludes(merge);
    unit->excludes(merge);
    cmd->callback([a] {
        ExperimentConfig ex = load_experiment(a->experiment, builtin_methods());
        if (!a->scenes.empty() || !a->integrators.empty()) ex = select_subset(ex, a->scenes, a->integrators);
        check_run_directory(ex, a->output);
        if (a->check) {
            print_plan(ex, a->output.empty() ? ex.output_dir : a->output, a->deviations_dir);
            return;
        }
        RunOptions options;
        options.output_dir = a->output;
        options.force.insert(a->force.begin(), a->force.end());
        options.reuse = a->reuse;
        if (!a->unit.empty()) {
            const RunResult r = run_unit(ex, a->unit, options);
            std::printf("unit %s: %d stages run, %d cached, %.1f s\n", a->unit.c_str(), r.stages_run, r.stages_cached,
                        r.seconds);
            return;
        }
        const RunResult r = a->merge ? merge_units(ex, options) : run_experiment(ex, options);
        std::printf("experiment %s: %d stages run, %d cached, %.1f s\n", ex.name.c_str(), r.stages_run, r.stages_cached,
                    r.seconds);
        std::printf("run directory: %s\n", r.run_dir.c_str());
        std::printf("tables:\n");
        for (const auto& t : r.tables) std::printf("  %s\n", t.c_str());
        if (!r.figures.empty()) {
            std::printf("figures:\n");
            for (const auto& f : r.figures) std::printf("  %s\n", f.c_str());
        }
    });
}

} // namespace lb::cli
