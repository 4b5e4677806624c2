#include "core/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <thread>

#include "core/error.hpp"

extern char** environ;

namespace lb {

int run_process(const std::vector<std::string>& argv, const ProcessOptions& options)
{
    if (argv.empty()) throw Error("run_process: empty argument vector");
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    if (!options.stdout_path.empty())
        posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, options.stdout_path.c_str(),
                                         O_WRONLY | O_CREAT | (options.append_stdout ? O_APPEND : O_TRUNC), 0644);
    if (!options.stderr_path.empty())
        posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, options.stderr_path.c_str(),
                                         O_WRONLY | O_CREAT | O_APPEND, 0644);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw Error("cannot run '" + argv[0] + "': " + std::strerror(rc));
    int status = 0;
    const auto start = std::chrono::steady_clock::now();
    auto pause = std::chrono::microseconds(500);
    for (;;) {
        const pid_t done = waitpid(pid, &status, options.timeout_seconds > 0.0 ? WNOHANG : 0);
        if (done == pid) break;
        if (done < 0) {
            if (errno == EINTR) continue;
            throw Error("waiting for '" + argv[0] + "' failed: " + std::strerror(errno));
        }
        const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
        if (elapsed.count() > options.timeout_seconds) {
            ::kill(pid, SIGKILL);
            while (waitpid(pid, &status, 0) < 0 && errno == EINTR) { }
            return kProcessTimedOut;
        }
        std::this_thread::sleep_for(pause);
        pause = std::min(pause * 2, std::chrono::microseconds(20000));
    }
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return -1;
}

} // namespace lb

namespace lb {

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const std::vector<std::string>& extra_env)
    : m_program(argv.empty() ? "" : argv[0])
{
    if (argv.empty()) throw Error("ChildProcess: empty argument vector");
    int to_child[2], from_child[2];
    if (pipe2(to_child, O_CLOEXEC) != 0) throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
    if (pipe2(from_child, O_CLOEXEC) != 0) {
        ::close(to_child[0]);
        ::close(to_child[1]);
        throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
    }
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    std::vector<std::string> env_text = extra_env;
    std::vector<char*> env;
    for (std::string& e : env_text) env.push_back(e.data());
    for (char** e = environ; *e; ++e) {
        const char* eq = std::strchr(*e, '=');
        const std::string name(*e, eq ? size_t(eq - *e) : std::strlen(*e));
        const bool replaced = std::any_of(extra_env.begin(), extra_env.end(), [&](const std::string& x) {
            return x.compare(0, name.size() + 1, name + "=") == 0;
        });
        if (!replaced) env.push_back(*e);
    }
    env.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, to_child[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, from_child[1], STDOUT_FILENO);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
    posix_spawn_file_actions_destroy(&actions);
    ::close(to_child[0]);
    ::close(from_child[1]);
    if (rc != 0) {
        ::close(to_child[1]);
        ::close(from_child[0]);
        throw Error("cannot run '" + argv[0] + "': " + std::strerror(rc));
    }
    m_pid = pid;
    m_in = to_child[1];
    m_out = from_child[0];
}

ChildProcess::~ChildProcess()
{
    try {
        finish(2.0);
    } catch (...) {  // a destructor does not throw; the program has been reaped or killed
    }
}

bool ChildProcess::write_all(const void* data, size_t size)
{
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        // MSG_NOSIGNAL is for sockets; a pipe whose reader exited raises SIGPIPE, so block it.
        sigset_t block, old;
        sigemptyset(&block);
        sigaddset(&block, SIGPIPE);
        pthread_sigmask(SIG_BLOCK, &block, &old);
        const ssize_t n = ::write(m_in, p, size);
        const int err = errno;
        if (n < 0 && err == EPIPE) {  // consume the pending SIGPIPE before unblocking
            const timespec zero{0, 0};
            sigtimedwait(&block, nullptr, &zero);
        }
        pthread_sigmask(SIG_SETMASK, &old, nullptr);
        if (n < 0) {
            if (err == EINTR) continue;
            if (err == EPIPE) return false;
            throw Error("writing to '" + m_program + "' failed: " + std::strerror(err));
        }
        p += n;
        size -= size_t(n);
    }
    return true;
}

bool ChildProcess::read_exact(void* data, size_t size)
{
    char* p = static_cast<char*>(data);
    while (size > 0) {
        const ssize_t n = ::read(m_out, p, size);
        if (n < 0) {
            if (errno == EINTR) continue;
            throw Error("reading from '" + m_program + "' failed: " + std::strerror(errno));
        }
        if (n == 0) return false;
        p += n;
        size -= size_t(n);
    }
    return true;
}

int ChildProcess::finish(double exit_grace_seconds)
{
    if (m_in >= 0) ::close(m_in), m_in = -1;
    if (m_pid > 0) {
        int status = 0;
        const auto start = std::chrono::steady_clock::now();
        for (;;) {
            const pid_t done = waitpid(m_pid, &status, WNOHANG);
            if (done == m_pid) break;
            if (done < 0 && errno != EINTR) break;
            const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
            if (elapsed.count() > exit_grace_seconds) {
                ::kill(m_pid, SIGKILL);
                while (waitpid(m_pid, &status, 0) < 0 && errno == EINTR) { }
                break;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        m_status = WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
        m_pid = -1;
    }
    if (m_out >= 0) ::close(m_out), m_out = -1;
    return m_status;
}

} // namespace lb
