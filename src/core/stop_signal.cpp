#include "core/stop_signal.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>

namespace lb {
namespace {

// Lock-free atomics: the only state the handler touches (async-signal-safe).
std::atomic<int> g_stop_points{0};
std::atomic<int> g_signal{0};
std::atomic<unsigned> g_seen{0};  ///< bit s: signal s arrived inside a stop point, not yet taken
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

constexpr int kStopSignals[] = {SIGTERM, SIGINT};

void set_default(int signal)
{
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    sigaction(signal, &action, nullptr);
}

extern "C" void on_stop_signal(int signal)
{
    const unsigned bit = 1u << unsigned(signal);
    if (g_stop_points.load() > 0 && !(g_seen.fetch_or(bit) & bit)) {
        // The first of this signal: stop at the safe point. Another kind of signal while one
        // is pending (Ctrl-C's SIGINT, then a driver's SIGTERM to its children) adds nothing.
        int none = 0;
        g_signal.compare_exchange_strong(none, signal);
        return;
    }
    // Outside a stop point, or the same signal again (Ctrl-C twice): the default action. The
    // signal is blocked while its handler runs, so the raise is delivered as it returns.
    set_default(signal);
    raise(signal);
}

} // namespace

void install_stop_handlers()
{
    for (int signal : kStopSignals) {
        // A signal the parent ignores (SIGINT in a shell's background job, nohup) stays ignored.
        struct sigaction current {};
        if (sigaction(signal, nullptr, &current) == 0 && current.sa_handler == SIG_IGN) continue;
        struct sigaction action {};
        action.sa_handler = on_stop_signal;
        sigemptyset(&action.sa_mask);
        action.sa_flags = SA_RESTART;  // blocking reads and writes resume rather than fail with EINTR
        sigaction(signal, &action, nullptr);
    }
}

StopPoint::StopPoint() { ++g_stop_points; }

StopPoint::~StopPoint()
{
    if (--g_stop_points == 0) {
        if (const int signal = g_signal.exchange(0)) terminate_by_signal(signal);
    }
}

int pending_stop_signal() { return g_signal.load(); }

int take_stop_signal()
{
    g_seen.store(0);
    return g_signal.exchange(0);
}

std::string signal_name(int signal)
{
    switch (signal) {
    case SIGTERM: return "SIGTERM";
    case SIGINT: return "SIGINT";
    default: return "signal " + std::to_string(signal);
    }
}

void terminate_by_signal(int signal)
{
    set_default(signal);
    sigset_t only;
    sigemptyset(&only);
    sigaddset(&only, signal);
    sigprocmask(SIG_UNBLOCK, &only, nullptr);
    raise(signal);
    std::_Exit(128 + signal);  // not reached: the default action of SIGTERM and SIGINT terminates
}

} // namespace lb
