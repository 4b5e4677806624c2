#pragma once
// The whole command line as a function: the executable (main.cpp) and the Python module
// (python/module.cpp, whose verbs are these subcommands run in-process) share it, so both
// accept the same options and report the same errors.
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace lb::cli {

/// Every subcommand and the global options (-j, -q, -v) on `app`.
void configure_app(CLI::App& app);

/// What one command line did: the status `latentbench` exits with, and the line it prints
/// on stderr on failure ("latentbench: error: ...", empty on success).
struct CliOutcome {
    int status = 0;
    std::string error;
    int stopped_by = 0;  ///< > 0: a training run stopped at a safe point on this signal (lb::Stopped)
};

/// Parse and run `args` (the arguments after the program name) on a fresh app named
/// `name`, catching what main catches: help is printed and gives 0; a usage error, an
/// lb::Error or a filesystem error gives 1 and its message; another exception 2.
CliOutcome run_command_line(const std::string& name, int argc, const char* const* argv);
CliOutcome run_command_line(const std::string& name, const std::vector<std::string>& args);

/// The long option names ("--epochs") and positional names ("data") of a subcommand;
/// empty if there is no such subcommand.
std::vector<std::string> subcommand_options(const std::string& subcommand);

} // namespace lb::cli
