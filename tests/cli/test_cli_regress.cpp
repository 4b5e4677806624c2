// `latentbench regress` through the CLI: exit 0 on an identical run, 1 on a
// regression (the rows named on stdout), 1 with the file named on bad input, and a
// JUnit file that Python's xml.etree parses with one testcase per compared row.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>

#include "eval/metrics.hpp"
#include "pipeline/report.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::run_program;
using testing::python_testcases;
namespace fs = std::filesystem;

/// A 60-frame rollout with relative RMSE `rmse`, non-finite from `stop` (0: never).
RolloutSummary rollout(double rmse, Index stop = 0)
{
    MatrixXd m = MatrixXd::Zero(60, kNumMetricColumns);
    m.col(kRmse).setConstant(rmse);
    m.col(kBcViolation).setConstant(1e-3);
    m.col(kKineticFreeGt).setConstant(1.0);
    m.col(kKineticFree).setConstant(1.0);
    if (stop > 0) m.bottomRows(60 - stop).setConstant(std::numeric_limits<double>::quiet_NaN());
    return summarize(m, 1.0, 30);
}

/// A run directory with one scene: methods `ours` (RMSE ours_rmse, diverging at
/// ours_stop) and, unless left out, `pca`.
std::string write_run(const std::string& name, double ours_rmse, Index ours_stop, bool with_pca = true)
{
    const std::string dir = fresh_dir("cli_regress_" + name);
    SceneResult r;
    r.label = "cloth_small";
    r.scene_name = "cloth";
    r.train_frames = 30;
    auto add = [&](const std::string& label, const RolloutSummary& s) {
        MethodResult m;
        m.name = label;
        m.method = label;
        m.summaries = {s};
        m.sequences = {"drop"};
        m.summary_seeds = {-1};
        r.methods.push_back(m);
    };
    add("ours", rollout(ours_rmse, ours_stop));
    if (with_pca) add("pca", rollout(0.02));
    ExperimentConfig ex;
    ex.paper_tables = false;
    write_tables(ex, {r}, dir + "/tables");
    return dir;
}


TEST(CliRegress, IdenticalRunPassesWithJunit)
{
    const std::string base = write_run("base", 0.01, 0);
    const std::string run = write_run("same", 0.01, 0);
    const std::string junit = run + "/gate.xml";
    const auto result = run_cli("regress " + run + " --baseline " + base + " --junit " + junit);
    EXPECT_EQ(result.exit_code, 0) << result.output;
    EXPECT_NE(result.output.find("**PASS**: 0 regressed, 0 improved, 4 unchanged, 0 missing, 0 new (4 rows)"),
              std::string::npos)
        << result.output;
    EXPECT_EQ(python_testcases(junit), 4);
}

TEST(CliRegress, RegressionExitsOneAndNamesTheRows)
{
    const std::string base = write_run("base", 0.01, 0);
    const std::string run = write_run("diverged", 0.01, 40, /*with_pca=*/false);
    const std::string junit = run + "/gate.xml";
    const auto result = run_cli("regress " + run + " --baseline " + base + " --junit " + junit);
    EXPECT_EQ(result.exit_code, 1) << result.output;
    EXPECT_NE(result.output.find("**FAIL**: 2 regressed"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("- cloth_small / ours / train: diverged 0/1 seeds -> 1/1 seeds (newly diverged)"),
              std::string::npos)
        << result.output;
    EXPECT_NE(result.output.find("- cloth_small / ours / test:"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("Missing in the run"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("- cloth_small / pca / test"), std::string::npos) << result.output;
    EXPECT_EQ(python_testcases(junit), 4);  // ours × 2 compared, pca × 2 missing (skipped)

    // The reverse is an improvement: exit 0; the row the baseline lacks is new.
    const auto reverse = run_cli("regress " + base + " --baseline " + run);
    EXPECT_EQ(reverse.exit_code, 0) << reverse.output;
    EXPECT_NE(reverse.output.find("**PASS**: 0 regressed, 2 improved, 0 unchanged, 0 missing, 2 new"), std::string::npos)
        << reverse.output;
    // A missing row fails only when asked to.
    const auto strict = run_cli("regress " + base + " --baseline " + base + "/tables --fail-on-missing");
    EXPECT_EQ(strict.exit_code, 0) << strict.output;
    const std::string no_pca = write_run("no_pca", 0.01, 0, /*with_pca=*/false);
    const auto lenient = run_cli("regress " + no_pca + " --baseline " + base);
    EXPECT_EQ(lenient.exit_code, 0) << lenient.output;
    const auto strict_missing = run_cli("regress " + no_pca + " --baseline " + base + " --fail-on-missing");
    EXPECT_EQ(strict_missing.exit_code, 1) << strict_missing.output;
    EXPECT_NE(strict_missing.output.find("**FAIL**: 0 regressed, 0 improved, 2 unchanged, 2 missing"), std::string::npos)
        << strict_missing.output;
}

TEST(CliRegress, FlagsWidenTheBands)
{
    const std::string base = write_run("base", 0.01, 0);
    // 40 % more error: above 0.01 · 1.25 + 1e-4 by default, inside 0.01 · 1.5 + 1e-4 with --relative 0.5
    const std::string drift = write_run("drift", 0.014, 0);
    EXPECT_EQ(run_cli("regress " + drift + " --baseline " + base).exit_code, 1);
    const auto loose = run_cli("regress " + drift + " --baseline " + base + " --relative 0.5");
    EXPECT_EQ(loose.exit_code, 0) << loose.output;
    EXPECT_NE(loose.output.find("mean_rmse 50 % + 0.0001"), std::string::npos) << loose.output;
    // a blow-up 19 frames earlier (both runs diverge, so the divergence check is satisfied):
    // caught by default, allowed with --horizon-frames 30
    const std::string early = write_run("early", 0.01, 40);
    const auto r = run_cli("regress " + early + " --baseline " + write_run("late", 0.01, 59) + " --horizon-frames 30");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("stable_horizon 0 % + 30 (higher is better)"), std::string::npos) << r.output;
    EXPECT_EQ(run_cli("regress " + early + " --baseline " + write_run("late", 0.01, 59)).exit_code, 1);
    const auto negative = run_cli("regress " + early + " --baseline " + base + " --relative -1");
    EXPECT_EQ(negative.exit_code, 1);
    EXPECT_NE(negative.output.find("--relative"), std::string::npos) << negative.output;
}

TEST(CliRegress, BadInputNamesTheFileAndExitsOne)
{
    const std::string base = write_run("base", 0.01, 0);
    const std::string empty = fresh_dir("cli_regress_empty");
    auto r = run_cli("regress " + empty + " --baseline " + base);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("latentbench: error: " + empty + ": no rollouts_*.csv nor methods_*.csv"),
              std::string::npos)
        << r.output;

    const std::string broken = write_run("broken", 0.01, 0);
    const std::string table = broken + "/tables/rollouts_cloth_small.csv";
    std::ofstream(table, std::ios::app) << "\"unterminated\n";
    r = run_cli("regress " + broken + " --baseline " + base);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find(table), std::string::npos) << r.output;

    const std::string tolerance = empty + "/tolerance.toml";
    testing::write_file(tolerance, "[metrics.mean_rmse]\nrelative = \"a lot\"\n");
    const std::string junit = empty + "/gate.xml";
    r = run_cli("regress " + base + " --baseline " + base + " --tolerance " + tolerance + " --junit " + junit);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("metrics.mean_rmse.relative"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(junit));

    r = run_cli("regress " + base);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_NE(r.output.find("baseline"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("required"), std::string::npos) << r.output;
}

} // namespace
} // namespace lb
