// `latentbench regress RUN_DIR --baseline BASELINE_DIR`: the stability regression gate
// (pipeline/regress.hpp). Markdown on stdout, JUnit XML with --junit, exit 1 on a
// regression.
#include <cstdio>

#include "cli/commands.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/regress.hpp"
#include "pipeline/regress_report.hpp"

namespace lb::cli {

void register_regress(CLI::App& app)
{
    struct Args {
        std::string run, baseline, tolerance, junit;
        bool fail_on_missing = false;
        double relative = -1.0;
        double horizon_frames = -1.0;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "regress", "Compare a finished run's metric tables with a baseline's; exit 1 on any regression");
    cmd->add_option("run", a->run, "The run directory (or its tables/ folder) to check")->required();
    cmd->add_option("-b,--baseline", a->baseline, "The baseline: a results/ folder or an earlier run directory")
        ->required();
    cmd->add_option("-t,--tolerance", a->tolerance,
                    "Tolerance file (TOML) over the defaults (README, \"Regression gate\")");
    cmd->add_option("--junit", a->junit, "Also write JUnit XML here (one testcase per row)");
    cmd->add_flag("--fail-on-missing", a->fail_on_missing,
                  "A baseline row the run lacks fails the gate (default: reported only)");
    cmd->add_option("--relative", a->relative,
                    "Relative tolerance of every gated error metric (over the tolerance file and the defaults)")
        ->check(CLI::Range(0.0, 1e6));
    cmd->add_option("--horizon-frames", a->horizon_frames,
                    "Frames every gated horizon may shrink by (absolute tolerance; relative set to 0)")
        ->check(CLI::Range(0.0, 1e9));
    cmd->callback([a] {
        GateOptions options = a->tolerance.empty() ? default_gate_options() : load_gate_options(a->tolerance);
        if (a->fail_on_missing) options.fail_on_missing = true;
        for (GateMetric& m : options.metrics) {
            if (!m.higher_is_better && a->relative >= 0.0) m.relative = a->relative;
            if (m.higher_is_better && a->horizon_frames >= 0.0) {
                m.relative = 0.0;
                m.absolute = a->horizon_frames;
            }
        }
        const std::vector<GateRow> baseline = load_gate_rows(a->baseline);
        const std::vector<GateRow> now = load_gate_rows(a->run);
        const GateReport report = compare_gate_rows(baseline, now, options);
        if (!a->junit.empty()) write_text_atomically(a->junit, gate_junit(report));
        std::fputs(gate_markdown(report, a->run, a->baseline).c_str(), stdout);
        std::fflush(stdout);
        set_exit_status(report.failed() ? 1 : 0);
    });
}

} // namespace lb::cli
