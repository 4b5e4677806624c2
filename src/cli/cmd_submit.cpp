#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/process.hpp"
#include "io/atomic_file.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/slurm.hpp"

namespace lb::cli {
namespace fs = std::filesystem;

namespace {

std::string read_file(const std::string& path)
{
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// sbatch with `args`; the job id it prints. Error with sbatch's message if it fails.
std::string submit_job(const std::string& sbatch, const std::vector<std::string>& args, const std::string& run_dir)
{
    const std::string out = run_dir + "/slurm/sbatch.out", err = run_dir + "/slurm/sbatch.err";
    fs::remove(err);
    std::vector<std::string> argv{sbatch};
    argv.insert(argv.end(), args.begin(), args.end());
    const int rc = run_process(argv, {out, err});
    if (rc != 0) throw Error("sbatch " + args.back() + " failed (exit " + std::to_string(rc) + "): " + read_file(err));
    return parse_sbatch_job_id(read_file(out));
}

} // namespace

void register_submit(CLI::App& app)
{
    struct Args {
        std::string experiment, output;
        SlurmOptions slurm;
        bool dry_run = false;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "submit", "Submit a suite to Slurm: one job array per dependency level, then a merge job (shared file system)");
    cmd->add_option("experiment", a->experiment, "Experiment TOML (experiments/*.toml)")->required();
    cmd->add_option("-o,--output", a->output, "Run directory on the shared file system (default: the experiment's output_dir)");
    cmd->add_option("--partition", a->slurm.partition, "Slurm partition (default: the cluster's)");
    cmd->add_option("--time", a->slurm.time, "Time limit per unit, e.g. 1:00:00 (default: the partition's)");
    cmd->add_option("--max-parallel", a->slurm.max_parallel, "Tasks of one array running at once (0: no limit)")
        ->check(CLI::Range(0, 100000));
    cmd->add_option("--cpus-per-task", a->slurm.cpus_per_task, "CPUs (and threads) per unit (default 1)")
        ->check(CLI::Range(1, 1024));
    cmd->add_flag("--dry-run", a->dry_run, "Print the sbatch scripts and commands; write and submit nothing");
    cmd->callback([a] {
        const ExperimentConfig ex = load_experiment(a->experiment, builtin_methods());
        check_run_directory(ex, a->output);  // before the dry run prints scripts for it
        const ExperimentPlan plan = plan_experiment(ex, resolve_run_dir(ex, a->output));
        a->slurm.latentbench = fs::read_symlink("/proc/self/exe").string();
        check_slurm_options(a->slurm, plan);
        const std::vector<SlurmJob> jobs = slurm_jobs(ex, plan, a->slurm);
        print_unit_plan(ex, plan, false);
        if (a->dry_run) {
            std::string previous;
            for (const SlurmJob& job : jobs) {
                std::printf("\n==> %s (%zu task%s)\n%s", job.script_path.c_str(), job.tasks, job.tasks == 1 ? "" : "s",
                            job.script.c_str());
                std::printf("--> sbatch");
                for (const std::string& arg : sbatch_arguments(job, previous)) std::printf(" %s", arg.c_str());
                std::printf("\n");
                previous = "<job id of " + job.name + ">";
            }
            std::printf("\ndry run: nothing written, nothing submitted\n");
            return;
        }
        std::string sbatch;
        try {
            sbatch = find_program("sbatch");
        } catch (const Error& e) {
            throw Error(std::string("submit: ") + e.what() + " (is Slurm installed here? --dry-run prints the scripts without it)");
        }
        write_text_atomically(plan.run_dir + "/manifest.jsonl", manifest_jsonl(ex, plan));
        write_text_atomically(plan.run_dir + "/experiment.toml", ex.toml_text);
        fs::create_directories(plan.run_dir + "/units");
        for (const SlurmJob& job : jobs) write_text_atomically(job.script_path, job.script);
        std::string previous, ids, submitted;
        for (const SlurmJob& job : jobs) {
            try {
                previous = submit_job(sbatch, sbatch_arguments(job, previous), plan.run_dir);
            } catch (const Error& e) {
                if (submitted.empty()) throw;
                throw Error(std::string(e.what()) + "\nalready submitted (cancel with scancel):" + submitted);
            }
            submitted += " " + previous;
            const std::string what = job.level >= 0 ? "level " + std::to_string(job.level) + " (" +
                                                          std::to_string(job.tasks) + " units)"
                                                    : std::string("merge");
            std::printf("submitted %s: job %s\n", what.c_str(), previous.c_str());
            ids += what + " " + previous + "\n";
        }
        write_text_atomically(plan.run_dir + "/slurm/jobs.txt", ids);
        std::printf("run directory: %s (units/<id>.log per unit; tables/ after the merge job %s)\n",
                    plan.run_dir.c_str(), previous.c_str());
    });
}

} // namespace lb::cli
