// latentbench: command-line entry point. See README.md for every subcommand.
#include <cstdio>
#include <exception>

#include <CLI/CLI.hpp>

#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"

int main(int argc, char** argv)
{
    CLI::App app{"latentbench: latent-space integrators for deformable simulation, benchmarked"};
    app.require_subcommand(1);
    bool quiet = false, verbose = false;
    int threads = 0;
    app.add_option("-j,--threads", threads, "Threads for parallel loops (default: all cores)");
    app.add_flag("-q,--quiet", quiet, "Only print errors and results");
    app.add_flag("-v,--verbose", verbose, "Print debug messages");
    app.parse_complete_callback([&] {
        lb::set_log_level(quiet ? lb::LogLevel::Quiet : verbose ? lb::LogLevel::Debug : lb::LogLevel::Info);
        if (threads > 0) lb::set_num_threads(threads);
    });
    lb::cli::register_simulate(app);
    lb::cli::register_info(app);
    lb::cli::register_train_integrator(app);
    lb::cli::register_rollout(app);
    lb::cli::register_evaluate(app);
    lb::cli::register_run(app);
    lb::cli::register_train_ae(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const lb::Error& e) {
        std::fprintf(stderr, "latentbench: error: %s\n", e.what());
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "latentbench: internal error: %s\n", e.what());
        return 2;
    }
    return 0;
}
