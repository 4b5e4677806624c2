#include <cstdio>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/run_status.hpp"

namespace lb::cli {

void register_status(CLI::App& app)
{
    struct Args {
        std::string experiment, output;
        bool all = false;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "status", "Say where a suite's run stands: each work unit's state, and the epoch a training unit has reached");
    cmd->add_option("experiment", a->experiment, "Experiment TOML (experiments/*.toml)")->required();
    cmd->add_option("-o,--output", a->output, "Run directory (default: the experiment's output_dir)");
    cmd->add_flag("--all", a->all, "List the units that are done too (default: only the others)");
    cmd->callback([a] {
        const ExperimentConfig ex = load_experiment(a->experiment, builtin_methods());
        check_run_directory(ex, a->output);
        const ExperimentPlan plan = plan_experiment(ex, resolve_run_dir(ex, a->output));
        std::fputs(format_run_status(ex.name, plan, run_status(plan), a->all).c_str(), stdout);
    });
}

} // namespace lb::cli
