// Stability regression: train and roll out the quickstart-size problems
// (experiments/stability.toml) and compare each method's stable horizon, mean
// RMSE and maximum boundary violation with the committed thresholds in
// results/stability_thresholds.toml. A failure names the scene, method and
// metric and says by how much it regressed. To update the thresholds
// deliberately, see README.md ("Stability regression").
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include <filesystem>

#include "core/log.hpp"
#include "baselines/builtin_methods.hpp"
#include "pipeline/experiment.hpp"
#include "io/hdf5.hpp"
#include "io/toml_config.hpp"

namespace lb {
namespace {

TEST(Stability, QuickstartSizeProblemsMeetCommittedThresholds)
{
    set_log_level(LogLevel::Quiet);
    const std::string root = LB_SOURCE_DIR;
    const ExperimentConfig ex = load_experiment(root + "/experiments/stability.toml", builtin_methods());
    RunOptions options;
    options.output_dir = std::string(LB_TEST_TMP_DIR) + "/stability_run";
    // Stage keys hash the configuration, not the code: a regression test must retrain
    // from scratch every time, never reuse an earlier run's stages.
    std::filesystem::remove_all(options.output_dir);
    const RunResult run = run_experiment(ex, options);

    const toml::table thresholds = parse_toml_file(root + "/results/stability_thresholds.toml");
    ConfigTable cfg(thresholds, "", "results/stability_thresholds.toml");
    cfg.accept("note");
    int checked = 0;
    for (ConfigTable t : cfg.table_array("threshold")) {
        const std::string scene = t.require_string("scene");
        const std::string method = t.require_string("method");
        const double min_horizon = t.require_double("min_stable_fraction");
        const double max_rmse = t.require_double("max_mean_rmse");
        const double max_bc = t.require_double("max_bc_violation");
        t.finish();
        const std::string file = run.run_dir + "/" + scene + "/rollouts/" + method + ".h5";
        ASSERT_TRUE(std::filesystem::exists(file)) << "no rollout for " << scene << "/" << method;
        const h5::File f = h5::File::open(file);
        for (long long k = 0; k < f.attribute_int("/", "num_rollouts"); ++k) {
            const std::string g = "rollouts/" + std::to_string(k);
            const std::string what = scene + "/" + method + " (" + f.attribute_string(g, "sequence") + ")";
            const double frames = double(f.attribute_int(g, "frames"));
            const double horizon = double(f.attribute_int(g, "stable_horizon")) / frames;
            // The test window's mean RMSE, the boundary violation over both windows (errors
            // are aggregated before the stable horizon; NaN, i.e. no frames, fails).
            const double rmse = f.attribute_double(g, "test_mean_rmse");
            const double bc_train = f.attribute_double(g, "train_max_bc_violation");
            const double bc_test = f.attribute_double(g, "test_max_bc_violation");
            const double bc = std::isnan(bc_train) ? bc_test : std::isnan(bc_test) ? bc_train : std::max(bc_train, bc_test);
            EXPECT_GE(horizon, min_horizon) << what << ": stable horizon " << horizon * frames << " of " << frames
                                            << " frames fell below the threshold " << min_horizon * frames
                                            << " (regressed by " << (min_horizon - horizon) * frames << " frames)";
            EXPECT_LE(rmse, max_rmse) << what << ": mean relative RMSE " << rmse << " exceeds the threshold " << max_rmse
                                      << " (regressed by " << 100.0 * (rmse / max_rmse - 1.0) << "%)";
            EXPECT_LE(bc, max_bc) << what << ": max boundary violation " << bc << " m exceeds the threshold " << max_bc
                                  << " m (regressed by " << 100.0 * (bc / max_bc - 1.0) << "%)";
            ++checked;
        }
    }
    cfg.finish();
    EXPECT_GT(checked, 0) << "no thresholds were checked";
}

} // namespace
} // namespace lb
