// A method added from outside the library (tests/methods/example_method.*) runs
// through the whole pipeline with one registration line: parsed from an experiment
// file, fitted, rolled out, and given its row in the comparison table.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "baselines/builtin_methods.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "example_method.hpp"
#include "pipeline/experiment.hpp"

namespace lb {
namespace {

namespace fs = std::filesystem;

const char* kSuite = R"(
name = "plugin"
[autoencoder]
hidden = [8]
pca = 4
epochs = 2
batch = 16
[[integrators]]
name = "cv"
method = "constant_velocity"
damping = 0.5
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

TEST(AddingAMethod, OneRegistrationLineRunsItThroughThePipeline)
{
    set_log_level(LogLevel::Quiet);
    MethodRegistry registry = builtin_methods();
    registry.add(example::constant_velocity_method());  // the one line

    const fs::path dir = fs::path(LB_TEST_TMP_DIR) / "plugin";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::ofstream(dir / "suite.toml") << kSuite;
    EXPECT_THROW(load_experiment((dir / "suite.toml").string(), builtin_methods()), ConfigError);  // unknown there

    const ExperimentConfig ex = load_experiment((dir / "suite.toml").string(), registry);
    RunOptions options;
    options.output_dir = (dir / "run").string();
    const RunResult r = run_experiment(ex, options);
    EXPECT_EQ(r.stages_run, 4);  // simulate, autoencoder, fit, rollout
    std::ifstream in(options.output_dir + "/tables/methods_cantilever_small.md");
    const std::string table((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(table.find("| cv "), std::string::npos) << table;
    EXPECT_NE(table.find("0.500000 (x_{t-1}"), std::string::npos) << table;

    std::ofstream(dir / "bad.toml") << std::string(kSuite).replace(std::string(kSuite).find("damping = 0.5"), 13, "damping = 2.0");
    try {
        load_experiment((dir / "bad.toml").string(), registry);
        FAIL() << "expected ConfigError";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("damping"), std::string::npos) << e.what();
    }
}

} // namespace
} // namespace lb
