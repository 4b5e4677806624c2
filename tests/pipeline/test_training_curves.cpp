// A suite writes tables/training_<scene>.csv: every training run's loss per epoch (the
// autoencoder with its physics fine-tuning, the latent MLP per seed, Tan et al.'s three
// stages), whose last value per run is the final_loss of its file; methods that train
// nothing have no rows. With matplotlib, scripts/plot_training.py draws one PNG per method.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>

#include "baselines/builtin_methods.hpp"
#include "core/log.hpp"
#include "core/process.hpp"
#include "io/hdf5.hpp"
#include "io/table.hpp"
#include "nn/training_curve.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/training_curves.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;

const char* kSuite = R"(
name = "curves"
seeds = [0, 1]
[autoencoder]
hidden = [16]
pca = 8
epochs = 12
batch = 16
learning_rate = 1.0e-3
physics_epochs = 2
[training]
epochs = 4
hidden = [16]
learning_rate = 1.0e-3
[[integrators]]
name = "ours"
[[integrators]]
name = "tan"
method = "tan_physics_mlp"
stage1_epochs = 2
stage2_epochs = 3
stage3_epochs = 2
window = 3
batch = 32
[[integrators]]
name = "pca"
method = "linear_pca"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[evaluation]
frames = 20
full_space = false
[outputs]
plots = false
paper_tables = false
)";

struct CurveRows {
    std::vector<double> train;  ///< the run's train_loss column, in order
    std::vector<std::string> stages;
    bool validation = false;
};

TEST(TrainingCurves, ASuiteWritesEveryRunsCurveEndingAtItsFinalLoss)
{
    set_log_level(LogLevel::Quiet);
    const std::string path = testing::write_in_fresh_dir("training_curves", "suite.toml", kSuite);
    RunOptions options;
    options.output_dir = fs::path(path).parent_path().string() + "/run";
    run_experiment(load_experiment(path, builtin_methods()), options);

    const std::string csv = options.output_dir + "/tables/training_cantilever_small.csv";
    ASSERT_TRUE(fs::exists(csv));
    const Table t = read_csv(csv);
    ASSERT_EQ(t.columns, (std::vector<std::string>{"method", "seed", "stage", "epoch", "train_loss", "validation_loss"}));
    std::map<std::string, CurveRows> runs;  // "method seed" -> its rows
    for (const auto& row : t.rows) {
        CurveRows& r = runs[row[0].text + " " + row[1].text];
        ASSERT_TRUE(row[4].value.has_value()) << row[4].text;
        if (r.stages.empty() || r.stages.back() != row[2].text) {
            r.stages.push_back(row[2].text);
            ASSERT_EQ(row[3].value.value_or(-1), 1.0) << "a stage starts at epoch 1";
        }
        r.train.push_back(*row[4].value);
        r.validation = r.validation || row[5].value.has_value();
    }
    // The autoencoder (its seed 0), the two seeds of each learned method; linear_pca trains nothing.
    ASSERT_EQ(runs.size(), 5u) << "runs: " << t.rows.size() << " rows";
    const std::string dir = options.output_dir + "/cantilever_small";
    const struct {
        const char* key;
        std::string file;
        std::vector<std::string> stages;
        std::size_t epochs;
    } expected[] = {
        {"autoencoder 0", dir + "/ae.h5", {"autoencoder", "physics"}, 0},  // early stopping may cut it
        {"ours 0", dir + "/integrators/ours.seed0.h5", {"integrator"}, 4},
        {"ours 1", dir + "/integrators/ours.seed1.h5", {"integrator"}, 4},
        {"tan 0", dir + "/integrators/tan.seed0.h5", {"stage1", "stage2", "stage3"}, 7},
        {"tan 1", dir + "/integrators/tan.seed1.h5", {"stage1", "stage2", "stage3"}, 7},
    };
    for (const auto& e : expected) {
        SCOPED_TRACE(e.key);
        ASSERT_TRUE(runs.count(e.key));
        const CurveRows& r = runs[e.key];
        EXPECT_EQ(r.stages, e.stages);
        if (e.epochs > 0) {
            EXPECT_EQ(r.train.size(), e.epochs);
        }
        for (double v : r.train) EXPECT_TRUE(std::isfinite(v) && v > 0.0) << v;
        // The file's final_loss is the curve's last value, in the file and in the table.
        const h5::File f = h5::File::open(e.file);
        const double final_loss = f.attribute_double("/", "final_loss");
        EXPECT_EQ(r.train.back(), final_loss);
        EXPECT_EQ(nn::last_train_loss(nn::load_training_curves(f, "")), final_loss);
    }
    EXPECT_TRUE(runs["autoencoder 0"].validation);  // the reconstruction stage validates
    EXPECT_FALSE(runs["ours 0"].validation);
    EXPECT_NE(runs["ours 0"].train, runs["ours 1"].train);  // two seeds, two runs
    EXPECT_FALSE(fs::exists(options.output_dir + "/figures"));  // plots = false

    // `latentbench info` summarises an artefact's curve.
    const auto info = testing::run_cli("info " + dir + "/integrators/ours.seed1.h5");
    EXPECT_EQ(info.exit_code, 0) << info.output;
    for (const char* part : {"method latent_mlp", "training curve, integrator: 4 epochs", "(the curve's last value)"})
        EXPECT_NE(info.output.find(part), std::string::npos) << part << " in " << info.output;
    const auto ae_info = testing::run_cli("info " + dir + "/ae.h5");
    for (const char* part : {"autoencoder of scene", "training curve, autoencoder:", "validation", "training curve, physics: 2 epochs"})
        EXPECT_NE(ae_info.output.find(part), std::string::npos) << part << " in " << ae_info.output;

    // The figures, if matplotlib is there (the scripts' own tests skip without it too).
    if (run_process({"/usr/bin/python3", "-c", "import matplotlib, numpy"}) != 0) {
        GTEST_SKIP() << "no matplotlib for /usr/bin/python3: figures not checked";
    }
    const std::string figures = options.output_dir + "/figures/cantilever_small";
    const std::vector<std::string> pngs =
        plot_training_curves({csv, figures, "cantilever_small", options.output_dir + "/run.log"});
    EXPECT_EQ(pngs.size(), 3u);
    for (const char* name : {"autoencoder", "ours", "tan"}) {
        const std::string png = figures + "/training_" + name + ".png";
        EXPECT_TRUE(fs::exists(png) && fs::file_size(png) > 1000) << png;
    }
}

} // namespace
} // namespace lb
