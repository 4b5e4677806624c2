#pragma once
// Running another program without a shell: the argument vector goes to
// posix_spawn as it is, so no file name or label is ever interpreted by a shell.
#include <string>
#include <vector>

namespace lb {

struct ProcessOptions {
    std::string stdout_path;  ///< "" : inherit; else written (truncated unless append_stdout)
    std::string stderr_path;  ///< "" : inherit; else appended to
    bool append_stdout = false;
    double timeout_seconds = 0.0;  ///< > 0: kill the program (SIGKILL) after this long
};

/// run_process's result for a program killed after ProcessOptions::timeout_seconds.
inline constexpr int kProcessTimedOut = -2;

/// Run argv[0] (an absolute path) with arguments argv[1..] and wait for it.
/// @return its exit status (128 + signal if it was killed; kProcessTimedOut if it ran
///         past options.timeout_seconds and was killed for it)
/// @throws Error if it cannot be started
int run_process(const std::vector<std::string>& argv, const ProcessOptions& options = {});

} // namespace lb
