#pragma once
// Where a suite's run stands (`latentbench status`): each work unit's state from its
// outputs' keys and its status file, and, for a unit that trains, the epoch its
// checkpoint has reached. Reads only; nothing is run, written or resumed.
#include <optional>
#include <string>
#include <vector>

#include "nn/training_loop.hpp"
#include "pipeline/plan.hpp"

namespace lb {

enum class UnitState {
    Done,         ///< every output exists with its key
    Running,      ///< its status says running and its process is alive on this host
    RunningElsewhere,  ///< its status says running on another host (not checked)
    Interrupted,  ///< its status says running, but its process is gone (killed, pre-empted)
    Stopped,      ///< stopped by SIGTERM or SIGINT at a safe point; the next run resumes it
    Failed,       ///< its status says failed (the detail says why)
    Stale,        ///< its status says done, but an output is missing or has another key
    NotStarted,   ///< no status yet
};
/// "done", "running", "running elsewhere", "interrupted", "stopped", "failed", "stale", "not started"
const char* unit_state_name(UnitState state);

struct UnitStatus {
    const Unit* unit = nullptr;
    UnitState state = UnitState::NotStarted;
    std::string where;   ///< the status file's second line: "<host> pid <pid> <date>"
    std::string detail;  ///< the status file's details (a failure's message), on one line
    /// The training checkpoint's progress, if the unit trains and has one (not for Done).
    std::optional<nn::CheckpointProgress> progress;
};

/// The state of every unit of `plan`, in plan order.
std::vector<UnitStatus> run_status(const ExperimentPlan& plan);

/// The report `latentbench status` prints: a summary line with the count of each state,
/// then one line per unit (`all_units`) or per unit that is not done.
std::string format_run_status(const std::string& suite_name, const ExperimentPlan& plan,
                              const std::vector<UnitStatus>& status, bool all_units);

} // namespace lb
