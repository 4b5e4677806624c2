#include "pipeline/slurm.hpp"

#include <unistd.h>

#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "core/error.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

/// Characters a path may have to appear in an #SBATCH line and, single-quoted, on the
/// command line of a batch script.
bool script_safe(const std::string& text)
{
    if (text.empty()) return false;
    for (unsigned char c : text) {
        if (std::isspace(c) || c == '\'' || c == '"' || c == '$' || c == '`' || c == '\\' || c < 0x20 || c == '%')
            return false;
    }
    return true;
}

bool matches(const std::string& text, const std::string& allowed_punctuation)
{
    if (text.empty()) return false;
    for (unsigned char c : text) {
        if (!std::isalnum(c) && allowed_punctuation.find(char(c)) == std::string::npos) return false;
    }
    return true;
}

} // namespace

void check_slurm_options(const SlurmOptions& o, const ExperimentPlan& plan)
{
    if (!o.partition.empty() && !matches(o.partition, "_-.,"))
        throw ConfigError("--partition '" + o.partition + "': letters, digits, '_', '-', '.' and ',' only");
    if (!o.time.empty() && !matches(o.time, ":-"))
        throw ConfigError("--time '" + o.time + "': Slurm's format, e.g. 30, 1:00:00 or 2-00:00:00");
    if (o.max_parallel < 0) throw ConfigError("--max-parallel must be >= 0 (0: no limit)");
    if (o.cpus_per_task < 1) throw ConfigError("--cpus-per-task must be >= 1");
    const std::pair<const char*, std::string> paths[] = {
        {"the run directory", plan.run_dir}, {"the suite file", plan.suite}, {"the latentbench program", o.latentbench}};
    for (const auto& [what, path] : paths) {
        if (!script_safe(path))
            throw ConfigError("submit: " + std::string(what) + " '" + path +
                              "' has characters a batch script cannot carry (whitespace, quotes, $, `, \\, %); "
                              "use another path (-o for the run directory)");
    }
}

std::vector<SlurmJob> slurm_jobs(const ExperimentConfig& ex, const ExperimentPlan& plan, const SlurmOptions& o)
{
    const std::string dir = plan.run_dir + "/slurm";
    auto header = [&](std::ostringstream& s, const std::string& name, const std::string& output) {
        s << "#!/bin/bash\n";
        s << "#SBATCH --job-name=" << name << "\n";
        s << "#SBATCH --output=" << output << "\n";
        s << "#SBATCH --cpus-per-task=" << o.cpus_per_task << "\n";
        if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
        if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
    };
    const std::string command = "'" + o.latentbench + "' -j " + std::to_string(o.cpus_per_task) + " run '" +
                                fs::absolute(plan.suite).string() + "' -o '" + plan.run_dir + "'";
    std::vector<SlurmJob> jobs;
    for (int level = 0; level < plan.levels(); ++level) {
        std::vector<std::string> ids;
        for (const Unit& u : plan.units) {
            if (u.level == level) ids.push_back(u.id);
        }
        SlurmJob job;
        job.level = level;
        job.name = "lb-" + ex.name + "-L" + std::to_string(level);
        job.script_path = dir + "/level" + std::to_string(level) + ".sbatch";
        job.tasks = ids.size();
        std::ostringstream s;
        header(s, job.name, dir + "/level" + std::to_string(level) + "-%A_%a.out");
        s << "#SBATCH --array=0-" << ids.size() - 1;
        if (o.max_parallel > 0) s << "%" << o.max_parallel;
        s << "\n";
        // A pre-empted task is requeued; the unit then resumes from its checkpoints (on
        // SIGTERM training checkpoints its epoch first). Appending keeps the output of every
        // run of the task: the stop, then the resume.
        s << "#SBATCH --requeue\n";
        s << "#SBATCH --open-mode=append\n";
        s << "# latentbench submit: level " << level << " of suite '" << ex.name << "', " << ids.size()
          << " work units. Array index i runs the unit with \"level\": " << level << ", \"array_index\": i in\n"
          << "# " << plan.run_dir << "/manifest.jsonl; its log is " << plan.run_dir << "/units/<id>.log.\n";
        s << "set -euo pipefail\n";
        s << "units=(";
        for (size_t i = 0; i < ids.size(); ++i) s << (i % 4 == 0 ? "\n  " : " ") << ids[i];
        s << "\n)\n";
        s << "exec " << command << " --unit \"${units[$SLURM_ARRAY_TASK_ID]}\"\n";
        job.script = s.str();
        jobs.push_back(std::move(job));
    }
    SlurmJob merge;
    merge.level = -1;
    merge.name = "lb-" + ex.name + "-merge";
    merge.script_path = dir + "/merge.sbatch";
    std::ostringstream s;
    header(s, merge.name, dir + "/merge-%j.out");
    s << "# latentbench submit: tables, figures and report of suite '" << ex.name << "' from its "
      << plan.units.size() << " work units.\n";
    s << "set -euo pipefail\n";
    s << "exec " << command << " --merge\n";
    merge.script = s.str();
    jobs.push_back(std::move(merge));
    return jobs;
}

std::vector<std::string> sbatch_arguments(const SlurmJob& job, const std::string& previous)
{
    std::vector<std::string> args{"--parsable"};
    if (!previous.empty()) {
        // A failed unit leaves the jobs after it unsatisfiable: cancel them rather than
        // leave them pending forever.
        args.push_back("--dependency=afterok:" + previous);
        args.push_back("--kill-on-invalid-dep=yes");
    }
    args.push_back(job.script_path);
    return args;
}

std::string parse_sbatch_job_id(const std::string& output)
{
    std::string id;
    for (char c : output) {
        if (std::isdigit(static_cast<unsigned char>(c))) {
            id += c;
        } else {
            break;
        }
    }
    const char next = id.size() < output.size() ? output[id.size()] : '\n';
    if (id.empty() || !(next == ';' || next == '\n' || next == '\r'))
        throw IoError("sbatch --parsable printed no job id: '" + output + "'");
    return id;
}

std::string find_program(const std::string& program)
{
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "/usr/bin:/bin");
    for (std::string d; std::getline(dirs, d, ':');) {
        if (d.empty()) continue;
        const fs::path candidate = fs::path(d) / program;
        if (::access(candidate.c_str(), X_OK) == 0 && !fs::is_directory(candidate)) return candidate.string();
    }
    throw Error("'" + program + "' is not on PATH");
}

} // namespace lb
