#include "pipeline/run_status.hpp"

#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

namespace lb {

namespace {

/// A status file's second line, "<host> pid <pid> <date>".
struct Where {
    std::string host, date;
    long pid = 0;
};
std::optional<Where> parse_where(const std::string& line)
{
    std::istringstream in(line);
    Where w;
    std::string pid_word;
    if (!(in >> w.host >> pid_word >> w.pid) || pid_word != "pid" || w.pid <= 0) return std::nullopt;
    std::getline(in >> std::ws, w.date);
    return w;
}

/// "pid 123 on host since <date>" (the line as it is if it does not parse).
std::string describe_where(const std::string& line)
{
    const std::optional<Where> w = parse_where(line);
    if (!w) return line;
    return "pid " + std::to_string(w->pid) + " on " + w->host + (w->date.empty() ? "" : " since " + w->date);
}

/// True if the status line names a process alive on this host; nullopt if it names
/// another host (or cannot be read).
std::optional<bool> process_alive(const std::string& line)
{
    const std::optional<Where> w = parse_where(line);
    if (!w) return std::nullopt;
    char here[256] = "";
    if (gethostname(here, sizeof here - 1) != 0 || w->host != here) return std::nullopt;
    return ::kill(pid_t(w->pid), 0) == 0 || errno == EPERM;
}

/// "12,345" for 12345.
std::string grouped(long long n)
{
    std::string digits = std::to_string(n < 0 ? -n : n), out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) out += ',';
        out += digits[i];
    }
    return (n < 0 ? "-" : "") + out;
}

/// "42 s", "17 min", "2.4 h".
std::string duration(double seconds)
{
    char text[32];
    if (seconds < 120) std::snprintf(text, sizeof text, "%.0f s", seconds);
    else if (seconds < 7200) std::snprintf(text, sizeof text, "%.0f min", seconds / 60);
    else std::snprintf(text, sizeof text, "%.1f h", seconds / 3600);
    return text;
}

std::string describe_progress(const nn::CheckpointProgress& p, bool active)
{
    std::string text = (p.trainer.empty() ? std::string("training") : p.trainer) + " at epoch " + grouped(p.epoch);
    if (p.epochs > 0) {
        char share[32];
        std::snprintf(share, sizeof share, " (%.1f %%)", 100.0 * p.epoch / p.epochs);
        text += " of " + grouped(p.epochs) + share;
    }
    text += " in its checkpoint";
    if (p.seconds >= 0) {
        text += ", " + duration(p.seconds) + " of training";
        if (active && p.epochs > p.epoch && p.epoch > 0)
            text += ", about " + duration(p.seconds / p.epoch * (p.epochs - p.epoch)) + " left at its mean rate";
    }
    return text;
}

} // namespace

const char* unit_state_name(UnitState state)
{
    switch (state) {
    case UnitState::Done: return "done";
    case UnitState::Running: return "running";
    case UnitState::RunningElsewhere: return "running elsewhere";
    case UnitState::Interrupted: return "interrupted";
    case UnitState::Stopped: return "stopped";
    case UnitState::Failed: return "failed";
    case UnitState::Stale: return "stale";
    case UnitState::NotStarted: return "not started";
    }
    return "?";
}

std::vector<UnitStatus> run_status(const ExperimentPlan& plan)
{
    std::vector<UnitStatus> out;
    out.reserve(plan.units.size());
    for (const Unit& u : plan.units) {
        UnitStatus s;
        s.unit = &u;
        if (unit_complete(u)) {
            s.state = UnitState::Done;
            out.push_back(s);
            continue;
        }
        const std::optional<UnitStatusRecord> record = read_unit_status(plan.run_dir, u.id);
        const std::string status = record ? record->status : "";
        if (record) {
            s.where = record->where;
            s.detail = record->detail;
        }
        if (status.empty()) s.state = UnitState::NotStarted;
        else if (status == "failed") s.state = UnitState::Failed;
        else if (status == "stopped") s.state = UnitState::Stopped;
        else if (status == "done") s.state = UnitState::Stale;
        else if (status == "running") {
            const std::optional<bool> alive = process_alive(s.where);
            s.state = !alive ? UnitState::RunningElsewhere : *alive ? UnitState::Running : UnitState::Interrupted;
        } else {
            s.state = UnitState::Failed;
            s.detail = "unknown status '" + status + "'";
        }
        const std::string checkpoint = unit_checkpoint_path(u);
        if (!checkpoint.empty()) s.progress = nn::read_checkpoint_progress(checkpoint);
        out.push_back(s);
    }
    return out;
}

std::string format_run_status(const std::string& suite_name, const ExperimentPlan& plan,
                              const std::vector<UnitStatus>& status, bool all_units)
{
    constexpr UnitState kOrder[] = {UnitState::Done,        UnitState::Running, UnitState::RunningElsewhere,
                                    UnitState::Interrupted, UnitState::Stopped, UnitState::Failed,
                                    UnitState::Stale,       UnitState::NotStarted};
    std::map<UnitState, int> count;
    for (const UnitStatus& s : status) ++count[s.state];
    std::string text = "suite " + suite_name + " in " + plan.run_dir + ": " + std::to_string(status.size()) +
                       " work units";
    const char* separator = ": ";
    for (UnitState state : kOrder) {
        if (count[state] == 0) continue;
        text += separator + std::to_string(count[state]) + " " + unit_state_name(state);
        separator = ", ";
    }
    text += "\n";
    std::size_t width = 0;
    for (const UnitStatus& s : status) width = std::max(width, s.unit->id.size());
    for (const UnitStatus& s : status) {
        if (s.state == UnitState::Done && !all_units) continue;
        char head[512];
        std::snprintf(head, sizeof head, "  %-17s %-*s", unit_state_name(s.state), int(width), s.unit->id.c_str());
        std::string line = head;
        std::string note;
        switch (s.state) {
        case UnitState::Running: note = describe_where(s.where); break;
        case UnitState::RunningElsewhere: note = describe_where(s.where) + " (another host: not checked)"; break;
        case UnitState::Interrupted:
            note = describe_where(s.where) + ", which is gone (killed or pre-empted): run the suite again to resume";
            break;
        case UnitState::Stopped:
            note = s.progress || s.detail.empty() ? "stopped by a signal at a safe point; the next run resumes it"
                                                  : s.detail;
            break;
        case UnitState::Failed: note = s.detail + " (log: units/" + s.unit->id + ".log)"; break;
        case UnitState::Stale: note = "ran, but an output is missing or was made with another configuration"; break;
        default: break;
        }
        if (s.progress) {
            const bool active = s.state == UnitState::Running || s.state == UnitState::RunningElsewhere;
            note = describe_progress(*s.progress, active) + (note.empty() ? "" : "; " + note);
        }
        if (!note.empty()) line += "  " + note;
        while (!line.empty() && line.back() == ' ') line.pop_back();
        text += line + "\n";
    }
    return text;
}

} // namespace lb
