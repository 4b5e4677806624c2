#pragma once
// Each subcommand registers itself on the CLI11 app; its callback runs the work
// and throws lb::Error on bad input (main prints it and exits non-zero).
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "core/types.hpp"

namespace lb {
struct ExperimentConfig;
struct ExperimentPlan;
}

namespace lb::cli {

void register_simulate(CLI::App& app);
void register_info(CLI::App& app);
void register_methods(CLI::App& app);
void register_fit(CLI::App& app);
void register_rollout(CLI::App& app);
void register_diagnose(CLI::App& app);
void register_evaluate(CLI::App& app);
void register_run(CLI::App& app);
void register_train_ae(CLI::App& app);
void register_plan(CLI::App& app);
void register_status(CLI::App& app);
void register_submit(CLI::App& app);
void register_regress(CLI::App& app);
void register_page(CLI::App& app);

/// The exit status a command reports without an error (e.g. `regress`: 1 when the gate
/// fails); 0 unless a command sets it. main returns it after a successful parse.
void set_exit_status(int status);
int exit_status();

/// `info` on a method's artefact or an autoencoder file: print what it is and a summary of
/// its training curves; false (nothing printed) for any other file (a dataset).
bool describe_training_file(const std::string& path);

/// `plan` and `submit`: the sweep and the unit counts (and with list_units each unit).
void print_unit_plan(const ExperimentConfig& ex, const ExperimentPlan& plan, bool list_units);

/// `run`, `plan` and `submit`: IoError naming `what` (-o, or the suite's output_dir key) and
/// `dir` if the run directory cannot be one: it, or the nearest existing folder above it, is
/// something other than a folder. Called before anything is printed or written.
void check_run_directory(const std::string& dir, const std::string& what);
/// check_run_directory for a suite's resolved run directory: `output` if given (-o), else
/// the suite's output_dir (named as its key in the suite file).
void check_run_directory(const ExperimentConfig& ex, const std::string& output);

/// The --hidden option of train-ae: "256,256,256"; ConfigError naming
/// the option if malformed or empty.
std::vector<Index> parse_hidden_option(const std::string& text);

} // namespace lb::cli
