// train-integrator, rollout, evaluate.
#include <cstdio>

#include "cli/commands.hpp"

#include "baselines/linear_pca/linear_pca.hpp"
#include "core/error.hpp"
#include "core/parse.hpp"
#include "core/log.hpp"
#include "eval/rollout.hpp"
#include "integrators/trainer.hpp"
#include "io/hdf5.hpp"

namespace lb::cli {
std::vector<Index> parse_hidden_option(const std::string& text)
{
    const auto widths = parse_positive_list(text);
    if (!widths || widths->empty())
        throw ConfigError("--hidden: expected comma-separated positive widths such as 256,256,256 (got '" + text + "')");
    return *widths;
}

void register_train_integrator(CLI::App& app)
{
    struct Args {
        std::string data, ae, output, loss = "self_supervised", hidden, checkpoint;
        bool no_noise = false, no_balancing = false;
        int epochs = IntegratorTrainOptions{}.epochs;
        int batch = IntegratorTrainOptions{}.batch_size;
        double lr = IntegratorTrainOptions{}.learning_rate;
        double max_seconds = 0.0;
        std::uint64_t seed = 0;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("train-integrator", "Train a latent MLP integrator on a dataset's training frames");
    cmd->add_option("data", a->data, "Dataset HDF5 from `simulate`")->required();
    cmd->add_option("--ae", a->ae, "Autoencoder HDF5 from `train-ae`")->required();
    cmd->add_option("-o,--output", a->output, "Output integrator HDF5")->required();
    cmd->add_option("--loss", a->loss, "self_supervised (the paper) or supervised_l2 (baseline)");
    cmd->add_flag("--no-noise", a->no_noise, "Disable training noise (ablation)");
    cmd->add_flag("--no-balancing", a->no_balancing, "Disable data balancing (ablation)");
    cmd->add_option("--epochs", a->epochs, "Training epochs");
    cmd->add_option("--batch", a->batch, "Mini-batch size (before noise doubling)");
    cmd->add_option("--lr", a->lr, "Adam learning rate");
    cmd->add_option("--hidden", a->hidden, "Hidden widths, e.g. 256,256,256 (default: the paper's for the scene)");
    cmd->add_option("--seed", a->seed, "Random seed");
    cmd->add_option("--max-seconds", a->max_seconds, "Stop training after this many seconds");
    cmd->add_option("--checkpoint", a->checkpoint, "Checkpoint file (resumed if it exists)");
    cmd->callback([a] {
        const Dataset data = load_dataset(a->data);
        const PhysicsModel model(data.physics);
        auto ae = std::make_shared<Autoencoder>(Autoencoder::load(a->ae, data.physics));
        IntegratorTrainOptions o;
        o.loss = integrator_loss_from_string(a->loss);
        o.training_noise = !a->no_noise;
        o.data_balancing = !a->no_balancing;
        o.epochs = a->epochs;
        o.batch_size = a->batch;
        o.learning_rate = a->lr;
        o.seed = a->seed;
        o.max_seconds = a->max_seconds;
        o.checkpoint_path = a->checkpoint;
        o.hidden = a->hidden.empty() ? default_integrator_hidden(data.scene_name) : parse_hidden_option(a->hidden);
        o.progress = log_level() >= LogLevel::Info;
        if (o.epochs < 1) throw ConfigError("option --epochs must be at least 1");
        if (o.batch_size < 1) throw ConfigError("option --batch must be at least 1");
        if (!(o.learning_rate > 0.0)) throw ConfigError("option --lr must be positive");
        const TrainingSamples samples = make_training_samples(*ae, data);
        log_info("training %s on %ld samples", o.describe().c_str(), long(samples.size()));
        LatentMlpModel net = LatentMlpModel::create(ae->latent_dim(), samples.p.rows(), o.hidden, o.seed);
        IntegratorTrainer trainer(model, *ae, o);
        const IntegratorTrainSummary s = trainer.train(net, samples);
        h5::AtomicOutput out(a->output);
        {
            h5::File f = h5::File::create(out.temp_path());
            net.save(f, "integrator.");
            f.set_attribute("/", "dataset", a->data);
            f.set_attribute("/", "autoencoder", a->ae);
            f.set_attribute("/", "scene", data.scene_name);
            f.set_attribute("/", "epochs_run", (long long)s.epochs_run);
            f.set_attribute("/", "final_loss", s.final_loss);
            f.set_attribute("/", "train_seconds", s.seconds);
        }
        out.commit();
        std::printf("wrote %s: %s, %d epochs, final loss %.6g, %.1f s%s\n", a->output.c_str(), o.describe().c_str(),
                    s.epochs_run, s.final_loss, s.seconds, s.time_limited ? " (time limit)" : "");
    });
}

void print_summary_header() { std::printf("%s\n", format_summary_header().c_str()); }

void print_summary(const std::string& method, const std::string& sequence, const RolloutSummary& s)
{
    std::printf("%s\n", format_summary_row(method, sequence, s).c_str());
}

void register_rollout(CLI::App& app)
{
    struct Args {
        std::string data, ae, integrator, output, name, sequences = "test";
        int frames = 0;
        bool no_positions = false;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("rollout", "Roll out a trained integrator on a dataset's sequences and measure it");
    cmd->add_option("data", a->data, "Dataset HDF5")->required();
    cmd->add_option("--ae", a->ae, "Autoencoder HDF5 (latent MLP integrators)");
    cmd->add_option("--integrator", a->integrator,
                    "Integrator HDF5 from `train-integrator`, or a subspace from `fit-pca` (linear_pca baseline)")
        ->required();
    cmd->add_option("-o,--output", a->output, "Output rollout HDF5 (metrics per frame and summaries)")->required();
    cmd->add_option("--name", a->name, "Method label in tables (default: the integrator's loss)");
    cmd->add_option("--sequences", a->sequences, "test (default: sequences with frames beyond training), all, or a name");
    cmd->add_option("--frames", a->frames, "Roll out at most this many frames");
    cmd->add_flag("--no-positions", a->no_positions, "Do not store the rolled-out positions");
    cmd->callback([a] {
        const Dataset data = load_dataset(a->data);
        const PhysicsModel model(data.physics);
        std::unique_ptr<Integrator> integrator;
        if (LinearPcaSubspace::is_subspace_file(a->integrator)) {
            integrator = std::make_unique<LinearPcaIntegrator>(a->name.empty() ? "linear_pca" : a->name, model,
                                                               LinearPcaSubspace::load(a->integrator, data.physics),
                                                               LinearPcaOptions{});
        } else {
            if (a->ae.empty()) throw ConfigError("rollout: --ae is required for a latent MLP integrator (" + a->integrator + ")");
            auto ae = std::make_shared<Autoencoder>(Autoencoder::load(a->ae, data.physics));
            const h5::File f = h5::File::open(a->integrator);
            LatentMlpModel net = LatentMlpModel::load(f, "integrator.");
            const std::string name = a->name.empty() ? net.loss : a->name;
            integrator = std::make_unique<LatentMlpIntegrator>(name, ae, std::move(net));
        }
        std::vector<RolloutResult> results;
        RolloutOptions options;
        options.max_frames = a->frames;
        options.keep_positions = !a->no_positions;
        options.progress = log_level() >= LogLevel::Info;
        for (size_t k : select_sequences(data, a->sequences)) {
            results.push_back(rollout(*integrator, model, data.sequences[k], options));
        }
        save_rollouts(results, a->output, data.scene_toml);
        print_summary_header();
        for (const auto& r : results) print_summary(r.method, r.sequence, r.summary);
        std::printf("wrote %s\n", a->output.c_str());
    });
}

void register_fit_pca(CLI::App& app)
{
    struct Args {
        std::string data, output;
        long dim = 0;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("fit-pca", "Fit the linear PCA subspace of the linear_pca baseline to a dataset");
    cmd->add_option("data", a->data, "Dataset HDF5 from `simulate`")->required();
    cmd->add_option("-o,--output", a->output, "Output subspace HDF5 (roll it out with `rollout --integrator`)")->required();
    cmd->add_option("--dim", a->dim, "Subspace dimension (default: the scene's latent size)");
    cmd->callback([a] {
        if (a->dim < 0) throw ConfigError("--dim must be positive (got " + std::to_string(a->dim) + ")");
        const Dataset data = load_dataset(a->data);
        const Index dim = a->dim > 0 ? Index(a->dim) : default_latent_dim(data.scene_name);
        const LinearPcaSubspace s = LinearPcaSubspace::fit(data, dim);
        s.save(a->output);
        std::printf("wrote %s: scene %s, %ld features -> d = %ld, %.6f of the training variance\n", a->output.c_str(),
                    data.scene_name.c_str(), long(s.pca.basis.rows()), long(s.pca.dim()), s.pca.explained_fraction());
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

} // namespace lb::cli
