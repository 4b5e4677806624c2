#pragma once
// Minimal leveled logging to stderr plus a throttled progress line.
#include <chrono>
#include <string>

namespace lb {

enum class LogLevel { Quiet = 0, Info = 1, Debug = 2 };

void set_log_level(LogLevel level);
/// Also append every message (any level that is printed) to this file; "" stops.
void set_log_file(const std::string& path);
LogLevel log_level();

/// printf-style message to stderr, prefixed with "[latentbench]".
void log_info(const char* format, ...) __attribute__((format(printf, 1, 2)));
void log_debug(const char* format, ...) __attribute__((format(printf, 1, 2)));
void log_warn(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Progress reporter for long loops: prints "label  k/n  (eta)" at most every
/// `interval` seconds and once at the end.
class Progress {
public:
    /// @param first  items already done when this object is made (a resumed run): the ETA is
    ///               extrapolated from the items done since.
    Progress(std::string label, long total, double interval_seconds = 2.0, long first = 0);
    /// Report that `done` items are finished; `extra` is appended to the line.
    void update(long done, const std::string& extra = "");
    void finish(const std::string& extra = "");

private:
    std::string m_label;
    long m_total;
    long m_first;
    double m_interval;
    std::chrono::steady_clock::time_point m_start;
    std::chrono::steady_clock::time_point m_last;
};

} // namespace lb
