// latentbench: command-line entry point. See README.md for every subcommand.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>

#include "cli/app.hpp"
#include "core/allocator.hpp"
#include "core/build_info.hpp"
#include "core/stop_signal.hpp"

namespace {
// Thread environment: OpenMP threads that spin-wait while OpenBLAS's own threads
// (inside CHOLMOD) want the same cores made the 10k-DOF Armadillo step 3× slower
// (683 → 240 ms) and the bunny 9× slower. libgomp reads OMP_WAIT_POLICY when it is
// loaded, before main, so set the defaults (unless the user chose otherwise) and
// re-execute once.
void ensure_thread_environment(char** argv)
{
    if (std::getenv("LB_THREAD_ENV")) return;
    setenv("OMP_WAIT_POLICY", "PASSIVE", 0);
    setenv("OPENBLAS_NUM_THREADS", "1", 0);
    setenv("LB_THREAD_ENV", "1", 1);
    execv("/proc/self/exe", argv);  // returns only on failure: then run as we are
}
} // namespace

int main(int argc, char** argv)
{
    ensure_thread_environment(argv);
    lb::keep_freed_memory();
    lb::set_command_line(argc, argv);
    lb::install_stop_handlers();  // SIGTERM/SIGINT: training checkpoints its epoch, then stops
    // The subcommands, the global options and the errors: cli/app.cpp (shared with Python).
    const lb::cli::CliOutcome outcome = lb::cli::run_command_line("", argc, argv);
    if (!outcome.error.empty()) std::fprintf(stderr, "%s\n", outcome.error.c_str());
    if (outcome.stopped_by > 0) {
        // Stopped at a safe point (the message says where): end as the signal would have.
        std::fflush(stderr);
        lb::terminate_by_signal(outcome.stopped_by);
    }
    return outcome.status;
}
