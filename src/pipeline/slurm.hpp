#pragma once
// `latentbench submit`: a suite's work units (pipeline/plan.hpp) as Slurm job arrays,
// one per dependency level, chained with --dependency=afterok, and a final merge job.
// Each array task runs `latentbench run SUITE -o RUN --unit ID`, the array index
// mapped to the unit through the manifest's "array_index" (the script lists the ids in
// that order). Nodes must share the file system of the run directory. Nothing here
// runs a shell: sbatch is started through an argument vector (core/process.hpp).
#include <string>
#include <vector>

#include "pipeline/plan.hpp"

namespace lb {

struct SlurmOptions {
    std::string partition;   ///< "" : the cluster's default
    std::string time;        ///< per task, Slurm's format ("30", "1:00:00", "2-00:00:00"); "" : default
    int max_parallel = 0;    ///< tasks of one array running at once (0: no limit)
    int cpus_per_task = 1;   ///< also latentbench's -j
    std::string latentbench; ///< absolute path of the program the tasks run
};

/// One sbatch script: a level's job array, or the merge job (level -1).
struct SlurmJob {
    int level = -1;
    std::string name;         ///< --job-name
    std::string script_path;  ///< <run_dir>/slurm/level<L>.sbatch or merge.sbatch
    std::string script;
    size_t tasks = 1;
};

/// ConfigError naming the option if a partition, time or path cannot go into a batch
/// script as it is (whitespace, quotes, '$', newlines, ...).
void check_slurm_options(const SlurmOptions& options, const ExperimentPlan& plan);

/// The scripts, in submission order: level 0, 1, ..., then the merge.
std::vector<SlurmJob> slurm_jobs(const ExperimentConfig& ex, const ExperimentPlan& plan, const SlurmOptions& options);

/// The sbatch arguments after the program name for `job`, depending on `previous`
/// (the job id of the level before; "" for the first).
std::vector<std::string> sbatch_arguments(const SlurmJob& job, const std::string& previous);

/// The job id in `sbatch --parsable` output ("1234" or "1234;cluster"); IoError quoting
/// the output if there is none.
std::string parse_sbatch_job_id(const std::string& output);

/// The absolute path of `program` on PATH; Error naming it if it is not there.
std::string find_program(const std::string& program);

} // namespace lb
