#include "cli/app.hpp"

#include <exception>
#include <filesystem>
#include <functional>
#include <memory>

#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/limits.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/stop_signal.hpp"

namespace lb::cli {

namespace {
int g_exit_status = 0;

CliOutcome run_parse(CLI::App& app, const std::function<void()>& parse)
{
    g_exit_status = 0;
    try {
        parse();
    } catch (const CLI::CallForHelp& e) {
        return {app.exit(e), ""};
    } catch (const CLI::CallForAllHelp& e) {
        return {app.exit(e), ""};
    } catch (const CLI::CallForVersion& e) {
        return {app.exit(e), ""};
    } catch (const CLI::ParseError& e) {
        // A usage error is the user's, like a bad file: exit 1 with the same prefix
        // (exit 2 is kept for internal errors).
        return {1, std::string("latentbench: error: ") + e.what() + " (see latentbench --help)"};
    } catch (const lb::Stopped& e) {
        // SIGTERM/SIGINT during training: the epoch was checkpointed (core/stop_signal.hpp).
        return {128 + e.signal(), std::string("latentbench: ") + e.what(), e.signal()};
    } catch (const lb::Error& e) {
        return {1, std::string("latentbench: error: ") + e.what()};
    } catch (const std::filesystem::filesystem_error& e) {
        // A path that cannot be made or written (a file where a directory must go, no
        // permission, a full disk) is the environment's, not a bug: exit 1 naming the path.
        return {1, std::string("latentbench: error: ") + e.what()};
    } catch (const std::exception& e) {
        return {2, std::string("latentbench: internal error: ") + e.what()};
    }
    return {g_exit_status, ""};
}
} // namespace

void set_exit_status(int status) { g_exit_status = status; }
int exit_status() { return g_exit_status; }

void configure_app(CLI::App& app)
{
    app.description("latentbench: latent-space integrators for deformable simulation, benchmarked");
    app.require_subcommand(1);
    struct Globals {
        bool quiet = false, verbose = false;
        int threads = 0;
    };
    auto g = std::make_shared<Globals>();
    app.add_option("-j,--threads", g->threads, "Threads for parallel loops (default: all cores)")
        ->check(CLI::Range(0, lb::kMaxThreads));
    app.add_flag("-q,--quiet", g->quiet, "Only print errors and results");
    app.add_flag("-v,--verbose", g->verbose, "Print debug messages");
    app.parse_complete_callback([g] {
        lb::set_log_level(g->quiet ? lb::LogLevel::Quiet : g->verbose ? lb::LogLevel::Debug : lb::LogLevel::Info);
        if (g->threads > 0) lb::set_num_threads(g->threads);
    });
    register_simulate(app);
    register_info(app);
    register_methods(app);
    register_fit(app);
    register_rollout(app);
    register_diagnose(app);
    register_evaluate(app);
    register_run(app);
    register_train_ae(app);
    register_plan(app);
    register_status(app);
    register_submit(app);
    register_regress(app);
    register_page(app);
}

CliOutcome run_command_line(const std::string& name, int argc, const char* const* argv)
{
    CLI::App app{"", name};
    configure_app(app);
    return run_parse(app, [&] { app.parse(argc, argv); });
}

CliOutcome run_command_line(const std::string& name, const std::vector<std::string>& args)
{
    CLI::App app{"", name};
    configure_app(app);
    std::vector<std::string> reversed(args.rbegin(), args.rend());  // CLI11 takes them last first
    return run_parse(app, [&] { app.parse(reversed); });
}

std::vector<std::string> subcommand_options(const std::string& subcommand)
{
    CLI::App app;
    configure_app(app);
    std::vector<std::string> names;
    const CLI::App* cmd = nullptr;
    try {
        cmd = app.get_subcommand(subcommand);
    } catch (const CLI::OptionNotFound&) {
        return names;
    }
    for (const CLI::Option* o : cmd->get_options()) {
        for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
        if (o->get_lnames().empty() && o->get_snames().empty() && !o->get_name().empty()) names.push_back(o->get_name());
    }
    return names;
}

} // namespace lb::cli
