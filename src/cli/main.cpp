// latentbench: command-line entry point. See README.md for every subcommand.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>

#include <CLI/CLI.hpp>

#include "cli/commands.hpp"
#include "core/allocator.hpp"
#include "core/build_info.hpp"
#include "core/error.hpp"
#include "core/limits.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
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

int g_exit_status = 0;
} // namespace

void lb::cli::set_exit_status(int status) { g_exit_status = status; }
int lb::cli::exit_status() { return g_exit_status; }

int main(int argc, char** argv)
{
    ensure_thread_environment(argv);
    lb::keep_freed_memory();
    lb::set_command_line(argc, argv);
    lb::install_stop_handlers();  // SIGTERM/SIGINT: training checkpoints its epoch, then stops
    CLI::App app{"latentbench: latent-space integrators for deformable simulation, benchmarked"};
    app.require_subcommand(1);
    bool quiet = false, verbose = false;
    int threads = 0;
    app.add_option("-j,--threads", threads, "Threads for parallel loops (default: all cores)")
        ->check(CLI::Range(0, lb::kMaxThreads));
    app.add_flag("-q,--quiet", quiet, "Only print errors and results");
    app.add_flag("-v,--verbose", verbose, "Print debug messages");
    app.parse_complete_callback([&] {
        lb::set_log_level(quiet ? lb::LogLevel::Quiet : verbose ? lb::LogLevel::Debug : lb::LogLevel::Info);
        if (threads > 0) lb::set_num_threads(threads);
    });
    lb::cli::register_simulate(app);
    lb::cli::register_info(app);
    lb::cli::register_methods(app);
    lb::cli::register_fit(app);
    lb::cli::register_rollout(app);
    lb::cli::register_diagnose(app);
    lb::cli::register_evaluate(app);
    lb::cli::register_run(app);
    lb::cli::register_train_ae(app);
    lb::cli::register_plan(app);
    lb::cli::register_submit(app);
    lb::cli::register_regress(app);
    lb::cli::register_page(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // A usage error is the user's, like a bad file: exit 1 with the same prefix
        // (exit 2 is kept for internal errors).
        std::fprintf(stderr, "latentbench: error: %s (see latentbench --help)\n", e.what());
        return 1;
    } catch (const lb::Stopped& e) {
        // Stopped at a safe point: say where, then end as the signal would have.
        std::fprintf(stderr, "latentbench: %s\n", e.what());
        std::fflush(stderr);
        lb::terminate_by_signal(e.signal());
    } catch (const lb::Error& e) {
        std::fprintf(stderr, "latentbench: error: %s\n", e.what());
        return 1;
    } catch (const std::filesystem::filesystem_error& e) {
        // A path that cannot be made or written (a file where a directory must go, no
        // permission, a full disk) is the environment's, not a bug: exit 1 naming the path.
        std::fprintf(stderr, "latentbench: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "latentbench: internal error: %s\n", e.what());
        return 2;
    }
    return lb::cli::exit_status();
}
