// `latentbench status`: each work unit's state, a stopped unit's checkpoint epoch, and the
// "stopped" status a signal leaves (pipeline/run_status.hpp).
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>

#include "baselines/builtin_methods.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/run_status.hpp"
#include "support/cli_runner.hpp"

extern char** environ;

namespace lb {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::write_in_fresh_dir;

/// The small cantilever with a tiny autoencoder and an integrator budget far beyond what
/// the test waits for: its fit is stopped by SIGTERM once its first checkpoint exists.
const char* kLong = R"(
name = "long_fit"
[autoencoder]
hidden = [16]
pca = 8
epochs = 20
batch = 16
learning_rate = 1.0e-3
[training]
epochs = 500000
hidden = [16]
learning_rate = 1.0e-3
[[integrators]]
name = "ours"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[evaluation]
frames = 40
[outputs]
plots = false
)";

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

std::string first_line(const std::string& path)
{
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    return line;
}

std::string hostname()
{
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    return host;
}

TEST(RunStatus, StoppedFitIsRecordedAsStoppedAndStatusSaysItsEpoch)
{
    const std::string suite = write_in_fresh_dir("run_status", "suite.toml", kLong);
    const std::string run_dir = fs::path(suite).parent_path().string() + "/run";
    const ExperimentConfig ex = load_experiment(suite, builtin_methods());
    const ExperimentPlan plan = plan_experiment(ex, run_dir);
    const Unit* fit = plan.find("fit.cantilever_small.ours");
    const Unit* reference = plan.find("eval.cantilever_small.full_space");
    const Unit* eval = plan.find("eval.cantilever_small.ours");
    ASSERT_TRUE(fit && reference && eval);
    EXPECT_EQ(unit_checkpoint_path(*eval), "");
    EXPECT_EQ(unit_checkpoint_path(*fit), fit->scene_dir + "/integrators/ours.checkpoint.h5");

    // Before anything ran, every unit is "not started".
    for (const UnitStatus& s : run_status(plan)) EXPECT_EQ(s.state, UnitState::NotStarted) << s.unit->id;

    ASSERT_EQ(run_cli("-q run " + suite + " -o " + run_dir + " --unit scene.cantilever_small").exit_code, 0);

    // The fit in a child process, stopped by SIGTERM once its first checkpoint exists (as a
    // cluster's pre-emption would).
    std::vector<std::string> args{LB_CLI_PATH, "-q", "run", suite, "-o", run_dir, "--unit", fit->id};
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    pid_t child = -1;
    ASSERT_EQ(posix_spawn(&child, argv[0], nullptr, nullptr, argv.data(), environ), 0);
    const std::string checkpoint = unit_checkpoint_path(*fit);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (!fs::exists(checkpoint) && std::chrono::steady_clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_TRUE(fs::exists(checkpoint)) << "no checkpoint after 120 s";
    // While it trains, its status says running, in a live process of this host.
    {
        const std::vector<UnitStatus> live = run_status(plan);
        const UnitStatus& s = live[size_t(fit - plan.units.data())];
        EXPECT_EQ(s.state, UnitState::Running) << read_all(unit_status_path(run_dir, fit->id));
    }
    ::kill(child, SIGTERM);
    int wstatus = 0;
    ASSERT_EQ(waitpid(child, &wstatus, 0), child);
    ASSERT_TRUE(WIFSIGNALED(wstatus)) << "exit status " << WEXITSTATUS(wstatus);
    EXPECT_EQ(WTERMSIG(wstatus), SIGTERM);
    EXPECT_EQ(first_line(unit_status_path(run_dir, fit->id)), "stopped");  // not "failed"

    // Two made-up status files: a "running" unit whose process is gone, and one on another host.
    {
        std::ofstream(unit_status_path(run_dir, reference->id))
            << "running\n" << hostname() << " pid 2147483646 2026-12-07 10:00:00 UTC\n\n";
        std::ofstream(unit_status_path(run_dir, eval->id)) << "running\nnode-that-is-not-here pid 12 2026-12-07 10:00:00 UTC\n\n";
    }

    const std::vector<UnitStatus> status = run_status(plan);
    ASSERT_EQ(status.size(), plan.units.size());
    const auto state_of = [&](const Unit* u) { return status[size_t(u - plan.units.data())]; };
    EXPECT_EQ(state_of(plan.find("scene.cantilever_small")).state, UnitState::Done);
    const UnitStatus stopped = state_of(fit);
    EXPECT_EQ(stopped.state, UnitState::Stopped);
    ASSERT_TRUE(stopped.progress.has_value());
    EXPECT_EQ(stopped.progress->trainer, "latent integrator");
    EXPECT_EQ(stopped.progress->epochs, 500000);
    EXPECT_GE(stopped.progress->epoch, 100);
    EXPECT_LT(stopped.progress->epoch, 500000);
    EXPECT_GT(stopped.progress->seconds, 0.0);
    EXPECT_EQ(state_of(reference).state, UnitState::Interrupted);
    EXPECT_EQ(state_of(eval).state, UnitState::RunningElsewhere);

    // The command prints the counts and each unit that is not done, the fit with its epoch.
    const auto printed = run_cli("status " + suite + " -o " + run_dir);
    EXPECT_EQ(printed.exit_code, 0) << printed.output;
    EXPECT_NE(printed.output.find("4 work units: 1 done, 1 running elsewhere, 1 interrupted, 1 stopped"),
              std::string::npos)
        << printed.output;
    EXPECT_NE(printed.output.find("of 500,000"), std::string::npos) << printed.output;
    EXPECT_NE(printed.output.find("the next run resumes it"), std::string::npos) << printed.output;
    EXPECT_NE(printed.output.find("which is gone"), std::string::npos) << printed.output;
    EXPECT_EQ(printed.output.find("  done "), std::string::npos) << printed.output;  // listed only with --all
    EXPECT_NE(run_cli("status --all " + suite + " -o " + run_dir).output.find("scene.cantilever_small"),
              std::string::npos);

    // The merge names the stopped unit as stopped, with the way to resume it.
    const auto merged = run_cli("-q run " + suite + " -o " + run_dir + " --merge");
    EXPECT_EQ(merged.exit_code, 1);
    EXPECT_NE(merged.output.find(fit->id + ": stopped on "), std::string::npos) << merged.output;
    EXPECT_NE(merged.output.find("run the suite again to resume it"), std::string::npos) << merged.output;
}

TEST(RunStatus, CheckpointProgressIsNulloptForFilesThatAreNotCheckpoints)
{
    const std::string dir = testing::fresh_dir("run_status_not_checkpoints");
    EXPECT_FALSE(nn::read_checkpoint_progress(dir + "/missing.h5").has_value());
    testing::write_file(dir + "/text.h5", "not HDF5");
    EXPECT_FALSE(nn::read_checkpoint_progress(dir + "/text.h5").has_value());
    EXPECT_FALSE(nn::read_checkpoint_progress(dir).has_value());
}

} // namespace
} // namespace lb
