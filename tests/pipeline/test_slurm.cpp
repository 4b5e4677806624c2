// `latentbench submit`'s scripts (issue 15), without a cluster; the real one runs in
// scripts/slurm_test.sh (ctest label slurm).
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "baselines/builtin_methods.hpp"
#include "core/error.hpp"
#include "pipeline/slurm.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

const char* kSuite = R"(
name = "arrays"
[autoencoder]
epochs = 5
[training]
epochs = 5
[[integrators]]
name = "ours"
[[integrators]]
name = "pca"
method = "linear_pca"
[[scenes]]
scene = "experiments/scenes/cantilever.toml"
variant = "small"
[sweep]
"training.noise_fraction" = [0.0, 0.1, 0.2]
)";

TEST(Slurm, OneArrayPerLevelChainedAndAMergeJob)
{
    const std::string dir = testing::fresh_dir("slurm_scripts");
    std::ofstream(dir + "/suite.toml") << kSuite;
    const ExperimentConfig ex = load_experiment(dir + "/suite.toml", builtin_methods());
    const ExperimentPlan plan = plan_experiment(ex, dir + "/run");
    SlurmOptions o;
    o.partition = "short";
    o.time = "0:30:00";
    o.max_parallel = 2;
    o.latentbench = LB_CLI_PATH;
    check_slurm_options(o, plan);
    const std::vector<SlurmJob> jobs = slurm_jobs(ex, plan, o);
    // levels: the scene; 3 + 1 fits and full_space's rollout; 4 rollouts; then the merge
    ASSERT_EQ(jobs.size(), 4u);
    EXPECT_EQ(jobs[1].tasks, 5u);
    EXPECT_NE(jobs[1].script.find("#SBATCH --array=0-4%2\n"), std::string::npos) << jobs[1].script;
    EXPECT_NE(jobs[1].script.find("#SBATCH --partition=short\n"), std::string::npos);
    EXPECT_NE(jobs[1].script.find("#SBATCH --time=0:30:00\n"), std::string::npos);
    EXPECT_NE(jobs[1].script.find("--unit \"${units[$SLURM_ARRAY_TASK_ID]}\""), std::string::npos);
    // Pre-empted tasks are requeued, and a requeued task's output is appended to, not replaced.
    EXPECT_NE(jobs[1].script.find("#SBATCH --requeue\n"), std::string::npos);
    EXPECT_NE(jobs[1].script.find("#SBATCH --open-mode=append\n"), std::string::npos);
    // The array order is the manifest's array_index order.
    size_t last = 0;
    for (const Unit& u : plan.units) {
        if (u.level != 1) continue;
        const size_t at = jobs[1].script.find(" " + u.id);
        ASSERT_NE(at, std::string::npos) << u.id;
        EXPECT_GT(at, last) << u.id;
        last = at;
    }
    EXPECT_EQ(jobs[3].level, -1);
    EXPECT_NE(jobs[3].script.find(" --merge\n"), std::string::npos) << jobs[3].script;
    EXPECT_EQ(jobs[3].script.find("--array"), std::string::npos);
    EXPECT_EQ(sbatch_arguments(jobs[0], ""), (std::vector<std::string>{"--parsable", jobs[0].script_path}));
    EXPECT_EQ(sbatch_arguments(jobs[2], "41"),
              (std::vector<std::string>{"--parsable", "--dependency=afterok:41", "--kill-on-invalid-dep=yes",
                                        jobs[2].script_path}));

    // What cannot go into a batch script as it is, is refused by name.
    SlurmOptions bad = o;
    bad.partition = "a b";
    EXPECT_THROW(check_slurm_options(bad, plan), ConfigError);
    bad = o;
    bad.time = "1;reboot";
    EXPECT_THROW(check_slurm_options(bad, plan), ConfigError);
    ExperimentPlan spaced = plan;
    spaced.run_dir = dir + "/my run";
    EXPECT_THROW(check_slurm_options(o, spaced), ConfigError);
}

TEST(Slurm, SbatchJobIdIsParsedOrRefused)
{
    EXPECT_EQ(parse_sbatch_job_id("1234\n"), "1234");
    EXPECT_EQ(parse_sbatch_job_id("77;cluster\n"), "77");
    EXPECT_THROW(parse_sbatch_job_id("sbatch: error: Batch job submission failed\n"), IoError);
    EXPECT_THROW(parse_sbatch_job_id("12x\n"), IoError);
    EXPECT_THROW(parse_sbatch_job_id(""), IoError);
}

TEST(Slurm, DryRunPrintsTheScriptsAndWritesNothing)
{
    const std::string dir = testing::fresh_dir("slurm_dry_run");
    std::ofstream(dir + "/suite.toml") << kSuite;
    const auto r = testing::run_cli("submit " + dir + "/suite.toml -o " + dir + "/run --dry-run --max-parallel 3");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("#SBATCH --array=0-4%3"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("--dependency=afterok:<job id of lb-arrays-L1>"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("dry run: nothing written, nothing submitted"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir + "/run"));
    const auto bad = testing::run_cli("submit " + dir + "/suite.toml -o " + dir + "/run --dry-run --partition a;b");
    EXPECT_EQ(bad.exit_code, 1) << bad.output;
    EXPECT_NE(bad.output.find("--partition 'a;b'"), std::string::npos) << bad.output;
}

/// A stand-in for sbatch on PATH: records its arguments, prints job ids 101, 102, ...
/// in --parsable form, and fails on call number `fail_on` (0: never).
std::string fake_sbatch(const std::string& dir, int fail_on)
{
    const std::string path = dir + "/bin/sbatch";
    std::filesystem::create_directories(dir + "/bin");
    std::ofstream(path) << "#!/usr/bin/python3\n"
                           "import pathlib, sys\n"
                           "log = pathlib.Path('" << dir << "/calls.txt')\n"
                           "calls = log.read_text().splitlines() if log.exists() else []\n"
                           "calls.append(' '.join(sys.argv[1:]))\n"
                           "log.write_text('\\n'.join(calls) + '\\n')\n"
                           "if len(calls) == " << fail_on << ":\n"
                           "    print('sbatch: error: invalid partition specified', file=sys.stderr)\n"
                           "    sys.exit(1)\n"
                           "print(f'{100 + len(calls)};cluster')\n";
    ::chmod(path.c_str(), 0755);
    return dir + "/bin";
}

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(Slurm, SubmitChainsTheLevelsAndTheMergeThroughSbatch)
{
    const std::string dir = testing::fresh_dir("slurm_submit");
    std::ofstream(dir + "/suite.toml") << kSuite;
    const std::string old_path = std::getenv("PATH") ? std::getenv("PATH") : "/usr/bin:/bin";
    setenv("PATH", (fake_sbatch(dir, 0) + ":" + old_path).c_str(), 1);
    const auto r = testing::run_cli("submit " + dir + "/suite.toml -o " + dir + "/run --max-parallel 2");
    setenv("PATH", old_path.c_str(), 1);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("submitted level 0 (1 units): job 101"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("submitted level 2 (4 units): job 103"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("submitted merge: job 104"), std::string::npos) << r.output;
    const std::string calls = read_all(dir + "/calls.txt");
    EXPECT_NE(calls.find("--parsable " + dir + "/run/slurm/level0.sbatch\n"), std::string::npos) << calls;
    EXPECT_NE(calls.find("--dependency=afterok:102 --kill-on-invalid-dep=yes " + dir + "/run/slurm/level2.sbatch"),
              std::string::npos) << calls;
    EXPECT_NE(calls.find("--dependency=afterok:103 --kill-on-invalid-dep=yes " + dir + "/run/slurm/merge.sbatch"),
              std::string::npos) << calls;
    EXPECT_NE(read_all(dir + "/run/slurm/level1.sbatch").find("#SBATCH --array=0-4%2"), std::string::npos);
    EXPECT_NE(read_all(dir + "/run/manifest.jsonl").find("\"array_index\":4"), std::string::npos);
    EXPECT_NE(read_all(dir + "/run/slurm/jobs.txt").find("merge 104"), std::string::npos);

    // sbatch refuses the third job: exit 1 with its message and the jobs to cancel.
    const std::string failing = testing::fresh_dir("slurm_submit_failing");
    std::ofstream(failing + "/suite.toml") << kSuite;
    setenv("PATH", (fake_sbatch(failing, 3) + ":" + old_path).c_str(), 1);
    const auto f = testing::run_cli("submit " + failing + "/suite.toml -o " + failing + "/run");
    setenv("PATH", old_path.c_str(), 1);
    EXPECT_EQ(f.exit_code, 1) << f.output;
    EXPECT_NE(f.output.find("invalid partition specified"), std::string::npos) << f.output;
    EXPECT_NE(f.output.find("already submitted (cancel with scancel): 101 102"), std::string::npos) << f.output;
}

} // namespace
} // namespace lb
