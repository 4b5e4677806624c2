// methods, fit, rollout, evaluate: every method through the registry.
#include <cstdio>
#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include "baselines/builtin_methods.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/limits.hpp"
#include "core/log.hpp"
#include "core/parse.hpp"
#include "eval/diagnose.hpp"
#include "eval/rollout.hpp"
#include "io/atomic_file.hpp"
#include "eval/summary_schema.hpp"
#include "io/hdf5.hpp"
#include "latent/autoencoder.hpp"
#include "methods/artefact.hpp"
#include "nn/weight_format.hpp"
#include "paper/scene_defaults.hpp"
#include "scene/scene.hpp"

namespace lb::cli {

std::vector<Index> parse_hidden_option(const std::string& text)
{
    const auto widths = parse_positive_list(text, kMaxWidth);
    if (!widths || widths->empty())
        throw ConfigError("--hidden: expected comma-separated widths in [1, " + std::to_string(kMaxWidth) +
                          "] such as 256,256,256 (got '" + text + "')");
    return *widths;
}

namespace {

/// `--set key=value` pairs as TOML text: a value that is not TOML (a bare word) is
/// taken as a string, so `--set loss=supervised_l2` and `--set hidden=[64,64]` both work.
std::string options_from_pairs(const std::vector<std::string>& pairs)
{
    std::string text;
    for (const std::string& pair : pairs) {
        const size_t eq = pair.find('=');
        if (eq == std::string::npos || eq == 0)
            throw ConfigError("--set: expected key=value (got '" + pair + "')");
        const std::string key = pair.substr(0, eq), value = pair.substr(eq + 1);
        const std::string line = key + " = " + value + "\n";
        try {
            parse_toml(line, "--set");
            text += line;
        } catch (const ConfigError&) {
            text += key + " = \"" + value + "\"\n";
            parse_toml(text, "--set " + pair);  // a bad key still fails, naming the pair
        }
    }
    return text;
}

/// The inputs a method gets from the command line for a dataset.
/// `loaded`: the autoencoder of `ae_path` if the caller has it already (not read again).
MethodInputs command_line_inputs(const Dataset& data, const PhysicsModel& model, const Method& method,
                                 const std::string& ae_path, const std::string& what,
                                 std::shared_ptr<Autoencoder> loaded = nullptr)
{
    MethodInputs in;
    in.data = &data;
    in.model = &model;
    in.progress = log_level() >= LogLevel::Info;
    if (method.needs_autoencoder()) {
        if (ae_path.empty())
            throw ConfigError(what + ": --ae is required for method '" + method.method_name() + "'");
        in.autoencoder = loaded ? std::move(loaded) : std::make_shared<Autoencoder>(Autoencoder::load(ae_path, data.physics));
        in.autoencoder_path = ae_path;
    }
    // The reference simulator uses the scene's own Newton settings, stored in the dataset.
    if (!method.has_artefact()) in.newton = load_scene_from_string(data.scene_toml, "dataset scene", ".").newton;
    return in;
}

Index scene_latent(const MethodInputs& in, const Dataset& data)
{
    return in.autoencoder ? in.autoencoder->latent_dim() : default_latent_dim(data.scene_name);
}

} // namespace

void register_methods(CLI::App& app)
{
    CLI::App* cmd = app.add_subcommand("methods", "List the methods this build can fit and roll out");
    cmd->callback([] {
        for (const MethodFactory& f : builtin_methods().all()) std::printf("%-16s %s\n", f.name.c_str(), f.description.c_str());
    });
}

void register_fit(CLI::App& app)
{
    struct Args {
        std::string method, data, ae, output, checkpoint;
        std::vector<std::string> set;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("fit", "Fit a method (train or precompute) on a dataset's training frames");
    cmd->add_option("data", a->data, "Dataset HDF5 from `simulate`")->required();
    cmd->add_option("--method", a->method, "Method name (`latentbench methods` lists them)")->required();
    cmd->add_option("--ae", a->ae, "Autoencoder HDF5 from `train-ae` (methods in latent space)");
    cmd->add_option("-o,--output", a->output, "Output artefact HDF5")->required();
    cmd->add_option("--set", a->set, "Method option key=value, as in an [[integrators]] entry (repeatable)");
    cmd->add_option("--checkpoint", a->checkpoint, "Training checkpoint (resumed only if it matches)");
    cmd->callback([a] {
        check_output_path(a->output, "-o");
        if (!a->checkpoint.empty()) check_output_path(a->checkpoint, "--checkpoint");
        const MethodRegistry& registry = builtin_methods();
        std::unique_ptr<Method> method = registry.parse_text(a->method, options_from_pairs(a->set), "--set");
        if (!method->has_artefact()) throw ConfigError("fit: method '" + a->method + "' has nothing to fit");
        const Dataset data = load_dataset(a->data);
        const PhysicsModel model(data.physics);
        MethodInputs in = command_line_inputs(data, model, *method, a->ae, "fit");
        in.checkpoint_path = a->checkpoint;
        in.dataset_path = a->data;
        method->resolve({data.scene_name, scene_latent(in, data)});
        try {
            fit_artefact(*method, in, data.scene_name, a->output, method->options_text());
        } catch (const NumericalError& e) {  // name the inputs: the message knows epoch and sample only
            throw NumericalError("fit --method " + a->method + " on '" + a->data + "'" +
                                 (a->ae.empty() ? "" : " with --ae '" + a->ae + "'") + ": " + e.what());
        }
        std::printf("wrote %s: %s (%s)\n", a->output.c_str(), method->method_name().c_str(), method->summary().c_str());
    });
}

static void print_summary_header() { std::printf("%s\n", format_summary_header().c_str()); }

/// Two lines per rollout: its training window and its test window.
static void print_summary(const std::string& method, const std::string& sequence, const RolloutSummary& s)
{
    for (const SummaryScope window : {SummaryScope::Train, SummaryScope::Test})
        std::printf("%s\n", format_summary_row(method, sequence, s, window).c_str());
}

void register_rollout(CLI::App& app)
{
    struct Args {
        std::string data, ae, integrator, method, output, name, sequences = "test", weights = "f32";
        long long frames = 0;  // range-checked before narrowing to int
        bool no_positions = false;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("rollout", "Roll out a fitted method on a dataset's sequences and measure it");
    cmd->add_option("data", a->data, "Dataset HDF5")->required();
    cmd->add_option("--integrator", a->integrator, "Artefact HDF5 from `fit` (it names its method and options)");
    cmd->add_option("--method", a->method, "A method with nothing to fit instead of --integrator (full_space)");
    cmd->add_option("--ae", a->ae, "Autoencoder HDF5 (methods in latent space)");
    cmd->add_option("-o,--output", a->output, "Output rollout HDF5 (metrics per frame and summaries)")->required();
    cmd->add_option("--name", a->name, "Method label in tables (default: the artefact's file name)");
    cmd->add_option("--sequences", a->sequences, "test (default: sequences with frames beyond training), all, or a name");
    cmd->add_option("--frames", a->frames, "Roll out at most this many frames");
    cmd->add_flag("--no-positions", a->no_positions, "Do not store the rolled-out positions");
    cmd->add_option("--weights", a->weights,
                    "Weights of the batch-1 float inference networks: f32 (default), f16 or int8 (latent_mlp, "
                    "tan_physics_mlp)");
    cmd->callback([a] {
        nn::WeightFormat weights;
        try {
            weights = nn::weight_format_from_string(a->weights);
        } catch (const std::invalid_argument& e) {
            throw ConfigError(std::string("rollout: --weights: ") + e.what());
        }
        if (a->integrator.empty() == a->method.empty())
            throw ConfigError("rollout: give either --integrator FILE (from `fit`) or --method NAME (nothing to fit)");
        check_output_path(a->output, "-o");
        const std::string frames_problem = rollout_frames_problem(a->frames);
        if (!frames_problem.empty()) throw ConfigError("rollout: --frames " + frames_problem);
        const MethodRegistry& registry = builtin_methods();
        const Dataset data = load_dataset(a->data);
        const PhysicsModel model(data.physics);
        std::unique_ptr<h5::File> artefact;
        std::unique_ptr<Method> method;
        if (!a->integrator.empty()) {
            artefact = std::make_unique<h5::File>(h5::File::open(a->integrator));
            method = method_from_artefact(registry, *artefact);
        } else {
            method = registry.parse_text(a->method, "", "--method");
            if (method->has_artefact())
                throw ConfigError("rollout: method '" + a->method + "' needs an artefact: fit it, then pass --integrator");
        }
        if (weights != nn::WeightFormat::f32 && !method->uses_weight_format())
            throw ConfigError("rollout: --weights " + a->weights + ": method '" + method->method_name() +
                              "' does not roll out through the float inference network (latent_mlp and "
                              "tan_physics_mlp do)");
        MethodInputs in = command_line_inputs(data, model, *method, a->ae, "rollout");
        in.weights = weights;
        method->resolve({data.scene_name, scene_latent(in, data)});
        const std::string label = !a->name.empty()       ? a->name
                                  : !a->integrator.empty() ? std::filesystem::path(a->integrator).stem().string()
                                                           : a->method;
        const std::unique_ptr<Integrator> integrator = method->load(in, artefact.get(), label);
        std::vector<RolloutResult> results;
        RolloutOptions options;
        options.max_frames = int(a->frames);
        options.keep_positions = !a->no_positions;
        options.progress = log_level() >= LogLevel::Info;
        for (size_t k : select_sequences(data, a->sequences)) {
            results.push_back(rollout(*integrator, model, data.sequences[k], options));
        }
        save_rollouts(results, a->output, data.scene_toml);
        print_summary_header();
        for (const auto& r : results) print_summary(r.method, r.sequence, r.summary);
        const std::string line = method->after_rollout(*integrator);
        if (!line.empty()) std::printf("%s: %s\n", method->method_name().c_str(), line.c_str());
        std::printf("wrote %s\n", a->output.c_str());
    });
}

void register_evaluate(CLI::App& app)
{
    auto files = std::make_shared<std::vector<std::string>>();
    CLI::App* cmd = app.add_subcommand("evaluate", "Print the summary table of one or more rollout files");
    cmd->add_option("rollouts", *files, "Rollout HDF5 files from `rollout`")->required();
    cmd->callback([files] {
        print_summary_header();
        for (const auto& path : *files) {
            for (const RolloutRecord& r : load_rollout_summaries(path)) print_summary(r.method, r.sequence, r.summary);
        }
    });
}

void register_diagnose(CLI::App& app)
{
    struct Args {
        std::string data, ae, output, sequences = "all";
        std::vector<std::string> integrators, rollouts;
        int stride = 1;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand(
        "diagnose", "Decompose a latent method's error: projection, stored energy, best step, one step, rollout");
    cmd->add_option("data", a->data, "Dataset HDF5")->required();
    cmd->add_option("--ae", a->ae, "Autoencoder HDF5 (rows a and b; needed by latent methods)")->required();
    cmd->add_option("--integrator", a->integrators,
                    "Artefact HDF5 from `fit` (repeatable): its one-step error from the truth; a fulton_full "
                    "artefact gives the manifold-optimal step (row c)");
    cmd->add_option("--rollouts", a->rollouts, "Rollout HDF5 from `rollout` (repeatable): row e");
    cmd->add_option("--sequences", a->sequences, "all (default), test, or a sequence name");
    cmd->add_option("--stride", a->stride, "Every stride-th frame (default 1)")->check(CLI::Range(1, 1000000));
    cmd->add_option("-o,--output", a->output, "Also write the table as OUTPUT.md, .csv and .tex");
    cmd->callback([a] {
        if (!a->output.empty()) check_output_path(a->output + ".md", "-o");
        const MethodRegistry& registry = builtin_methods();
        const Dataset data = load_dataset(a->data);
        const PhysicsModel model(data.physics);
        DiagnoseOptions options;
        options.sequences = select_sequences(data, a->sequences);
        options.stride = a->stride;
        Diagnosis diagnosis(model, data, options);
        auto autoencoder = std::make_shared<Autoencoder>(Autoencoder::load(a->ae, data.physics));
        diagnosis.add_autoencoder(*autoencoder);
        for (const std::string& path : a->integrators) {
            const h5::File artefact = h5::File::open(path);
            std::unique_ptr<Method> method = method_from_artefact(registry, artefact);
            const MethodInputs in = command_line_inputs(data, model, *method, a->ae, "diagnose", autoencoder);
            method->resolve({data.scene_name, scene_latent(in, data)});
            const std::string label = std::filesystem::path(path).stem().string();
            const std::unique_ptr<Integrator> integrator = method->load(in, &artefact, label);
            log_info("diagnose: one step from the truth with %s (%s)", label.c_str(), method->method_name().c_str());
            diagnosis.add_one_step(*integrator, one_step_stage(method->method_name()));
        }
        for (const std::string& path : a->rollouts) {
            std::vector<RolloutRecord> records = load_rollout_summaries(path);
            // one row per method in the file
            while (!records.empty()) {
                const std::string name = records.front().method;
                std::vector<RolloutRecord> mine;
                auto it = std::stable_partition(records.begin(), records.end(),
                                                [&](const RolloutRecord& r) { return r.method == name; });
                mine.assign(records.begin(), it);
                records.erase(records.begin(), it);
                diagnosis.add_rollout(mine);
            }
        }
        const Table table = diagnosis.table(data.scene_name);
        std::printf("%s", to_markdown(table).c_str());
        if (!a->output.empty()) {
            for (const std::string& p : write_table_files(table, a->output)) std::printf("wrote %s\n", p.c_str());
        }
    });
}

} // namespace lb::cli
