#include <cstdio>
#include <filesystem>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"

namespace lb::cli {

void check_run_directory(const std::string& dir, const std::string& what)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    for (fs::path p = fs::path(dir).lexically_normal(); !p.empty(); p = p.parent_path()) {
        if (fs::exists(p, ec)) {
            if (!fs::is_directory(p, ec))
                throw IoError(what + " '" + dir + "': the run directory " +
                              (p == fs::path(dir).lexically_normal() ? std::string("is an existing file")
                                                                     : "would be inside '" + p.string() + "', a file") +
                              ", not a directory; give a directory (it is created if missing)");
            return;
        }
        if (p == p.parent_path()) return;
    }
}

void check_run_directory(const ExperimentConfig& ex, const std::string& output)
{
    check_run_directory(resolve_run_dir(ex, output),
                        output.empty() ? ex.source + ": key 'output_dir'" : std::string("-o"));
}

void print_unit_plan(const ExperimentConfig& ex, const ExperimentPlan& plan, bool list_units)
{
    size_t count[3] = {0, 0, 0};
    for (const Unit& u : plan.units) ++count[int(u.kind)];
    const std::string points = ex.sweep.empty() ? "no sweep" : std::to_string(plan.points) + " sweep points";
    std::printf("suite %s: %s, %zu work units (%zu scene, %zu fit, %zu eval) in %d levels\n", ex.name.c_str(),
                points.c_str(), plan.units.size(), count[0], count[1], count[2], plan.levels());
    for (const SweepAxis& a : ex.sweep) {
        std::printf("  sweep %s:", a.key.c_str());
        for (const std::string& v : a.values) std::printf(" %s", v.c_str());
        std::printf("\n");
    }
    if (!list_units) return;
    for (const Unit& u : plan.units) {
        std::printf("  [%d.%d] %-40s %s%s%s\n", u.level, u.array_index, u.id.c_str(),
                    u.point_text.empty() ? "" : ("(" + u.point_text + ") ").c_str(),
                    u.depends_on.empty() ? "" : "after ", u.depends_on.empty() ? "" : u.depends_on.front().c_str());
    }
}

void register_plan(CLI::App& app)
{
    struct Args {
        std::string experiment, output, manifest;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "plan", "List a suite's independent work units and write its manifest (JSON Lines); runs nothing");
    cmd->add_option("experiment", a->experiment, "Experiment TOML (experiments/*.toml)")->required();
    cmd->add_option("-o,--output", a->output, "Run directory (default: the experiment's output_dir)");
    cmd->add_option("--manifest", a->manifest, "Manifest file (default: <run directory>/manifest.jsonl)");
    cmd->callback([a] {
        const ExperimentConfig ex = load_experiment(a->experiment, builtin_methods());
        check_run_directory(ex, a->output);
        const ExperimentPlan plan = plan_experiment(ex, resolve_run_dir(ex, a->output));
        const std::string manifest = a->manifest.empty() ? plan.run_dir + "/manifest.jsonl" : a->manifest;
        write_text_atomically(manifest, manifest_jsonl(ex, plan));
        print_unit_plan(ex, plan, true);
        std::printf("manifest: %s\n", manifest.c_str());
    });
}

} // namespace lb::cli
