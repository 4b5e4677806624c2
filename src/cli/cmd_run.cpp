#include <cstdio>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "pipeline/experiment.hpp"

namespace lb::cli {

void register_run(CLI::App& app)
{
    struct Args {
        std::string experiment, output;
        std::vector<std::string> force;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("run", "Run an experiment suite: simulate, train, roll out, tables, plots (cached stages)");
    cmd->add_option("experiment", a->experiment, "Experiment TOML (experiments/*.toml)")->required();
    cmd->add_option("-o,--output", a->output, "Run directory (default: the experiment's output_dir)");
    cmd->add_option("--force", a->force,
                    "Redo a stage even if cached: simulate, autoencoder, integrators, rollouts, tables, plots, all");
    cmd->callback([a] {
        const ExperimentConfig ex = load_experiment(a->experiment, builtin_methods());
        RunOptions options;
        options.output_dir = a->output;
        options.force.insert(a->force.begin(), a->force.end());
        const RunResult r = run_experiment(ex, options);
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
