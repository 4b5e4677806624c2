#pragma once
// Stopping at a safe point on SIGTERM or SIGINT: Slurm's pre-emption, `scontrol requeue`
// and `scancel` send SIGTERM (SIGKILL follows after the cluster's KillWait, 30 s by
// default), Ctrl-C sends SIGINT. Inside a stop point (a training loop) the signal only
// sets a flag: the loop finishes its epoch, writes its checkpoint and throws Stopped;
// `latentbench` prints the message and then terminates by the same signal, so a requeued
// or rerun job resumes from that epoch. Outside a stop point, and when the same signal comes
// again (Ctrl-C twice), it terminates the process at once, as it would without the handlers;
// SIGTERM after SIGINT (or the reverse) waits for the safe point like the first.
#include <string>

#include "core/error.hpp"

namespace lb {

/// Installs the SIGTERM and SIGINT handlers (the CLI, once at start; idempotent).
void install_stop_handlers();

/// While at least one exists (on any thread), SIGTERM and SIGINT are recorded instead of
/// terminating. Its destructor terminates the process by a recorded signal that nobody
/// took (take_stop_signal), so a signal is never lost.
class StopPoint {
public:
    StopPoint();
    ~StopPoint();
    StopPoint(const StopPoint&) = delete;
    StopPoint& operator=(const StopPoint&) = delete;
};

/// The signal recorded inside a stop point (0: none), without taking it.
int pending_stop_signal();
/// The recorded signal (0: none), taken: the caller stops and throws Stopped.
int take_stop_signal();

/// "SIGTERM", "SIGINT", or "signal <n>".
std::string signal_name(int signal);

/// A loop stopped at a safe point because of `signal` (its state is saved, the message says
/// where). main prints it and terminates by the signal.
class Stopped : public Error {
public:
    Stopped(int signal, const std::string& message) : Error(message), m_signal(signal) { }
    int signal() const { return m_signal; }

private:
    int m_signal;
};

/// Terminates the process by `signal` with its default action (no handler), as if the
/// signal had arrived without one: the parent (a shell, slurmstepd) sees the signal.
[[noreturn]] void terminate_by_signal(int signal);

} // namespace lb
