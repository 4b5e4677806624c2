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

namespace lb {

/// A program started with pipes on its standard input and output, for a request and
/// reply protocol (the Python method host, baselines/python_method/). No shell; stderr is
/// inherited. The destructor closes its input and waits for it (killing it after
/// `exit_grace_seconds`).
class ChildProcess {
public:
    /// @param argv  argv[0] an absolute path
    /// @param extra_env  "NAME=value" entries placed before this process's environment
    /// @throws Error if it cannot be started
    ChildProcess(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env);
    ~ChildProcess();
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    /// Write all of `size` bytes; false if the program closed its input (it exited).
    bool write_all(const void* data, size_t size);
    /// Read exactly `size` bytes; false on end of file (the program exited).
    bool read_exact(void* data, size_t size);
    /// Close the input and wait for the program: its exit status (128 + signal if killed).
    int finish(double exit_grace_seconds = 5.0);
    const std::string& program() const { return m_program; }

private:
    std::string m_program;
    int m_pid = -1;
    int m_in = -1;   ///< our end of the program's stdin
    int m_out = -1;  ///< our end of the program's stdout
    int m_status = -1;
};

} // namespace lb
