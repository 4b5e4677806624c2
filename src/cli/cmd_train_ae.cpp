#include <cstdio>

#include "paper/scene_defaults.hpp"
#include "cli/commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "io/atomic_file.hpp"
#include "latent/autoencoder.hpp"
#include "latent/autoencoder_option_table.hpp"
#include "sim/dataset.hpp"

namespace lb::cli {

namespace {

/// The range of `flag` from the option table the suite reader also checks against.
CLI::Validator table_range(const char* flag)
{
    const AutoencoderOptionSpec& spec = autoencoder_option_by_flag(flag);
    return CLI::Validator([&spec](std::string& text) { return spec.text_problem(text); }, spec.range_text());
}

} // namespace

void register_train_ae(CLI::App& app)
{
    struct Args {
        std::string data;
        std::string output;
        long latent = 0;  // 0 (not given): the scene's default
        int epochs = AutoencoderOptions{}.epochs;
        int batch = AutoencoderOptions{}.batch_size;
        double lr = AutoencoderOptions{}.learning_rate;
        long pca = long(AutoencoderOptions{}.pca_dim);
        std::string hidden = "200,200,200";
        std::uint64_t seed = AutoencoderOptions{}.seed;
        std::string checkpoint;
        int checkpoint_every = AutoencoderOptions{}.checkpoint_every;
        int patience = AutoencoderOptions{}.patience;
        double validation = AutoencoderOptions{}.validation_fraction;
        std::string frame = "translation";
        int physics_epochs = AutoencoderOptions{}.physics_epochs;
        double physics_weight = AutoencoderOptions{}.physics_weight;
        double physics_lr = AutoencoderOptions{}.physics_learning_rate;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("train-ae", "Train the BC-relative, PCA-initialised autoencoder on a dataset");
    cmd->add_option("data", args->data, "Dataset HDF5 file (from 'latentbench simulate')")->required();
    cmd->add_option("-o,--output", args->output, "Output autoencoder HDF5 file")->required();
    cmd->add_option("--latent", args->latent,
                    "Latent dimension (default per scene: rods 4, cloth 4, armadillo 12, bunny_ears 8, cantilever 4)")
        ->check(table_range("--latent"));
    cmd->add_option("--epochs", args->epochs, "Epochs (total, including resumed ones)")
        ->capture_default_str()
        ->check(table_range("--epochs"));
    cmd->add_option("--batch", args->batch, "Mini-batch size")->capture_default_str()->check(table_range("--batch"));
    cmd->add_option("--lr", args->lr, "Adam learning rate")->capture_default_str()->check(table_range("--lr"));
    cmd->add_option("--pca", args->pca, "Width of the PCA layers (clamped to frames − 1 and features; 0: none)")
        ->capture_default_str()
        ->check(table_range("--pca"));
    cmd->add_option("--hidden", args->hidden, "Decoder hidden widths after the latent; the encoder mirrors them")->capture_default_str();
    cmd->add_option("--seed", args->seed, "Seed of the initialisation and the shuffling")
        ->capture_default_str()
        ->check(table_range("--seed"));
    cmd->add_option("--checkpoint", args->checkpoint,
                    "Checkpoint file: written periodically, resumed from if it exists and matches");
    cmd->add_option("--checkpoint-every", args->checkpoint_every, "Epochs between checkpoints")
        ->capture_default_str()
        ->check(table_range("--checkpoint-every"));
    cmd->add_option("--patience", args->patience, "Early stopping patience in epochs (0: never)")
        ->capture_default_str()
        ->check(table_range("--patience"));
    cmd->add_option("--validation", args->validation,
                    "Fraction of training frames held out for validation (every k-th frame)")
        ->capture_default_str()
        ->check(table_range("--validation"));
    cmd->add_option("--frame", args->frame,
                    "Features' frame: translation (relative to the Dirichlet mean or rod roots, the paper's) or "
                    "rigid (the boundary's best-fit rotation removed as well)")
        ->capture_default_str()
        ->check(CLI::IsMember({"translation", "rigid"}));
    cmd->add_option("--physics-epochs", args->physics_epochs,
                    "Epochs of physics fine-tuning after training: L_recon + weight * L_ephys, the incremental "
                    "potential of the reconstructions (Tan et al.; 0: none)")
        ->capture_default_str()
        ->check(table_range("--physics-epochs"));
    cmd->add_option("--physics-weight", args->physics_weight, "Weight of L_ephys in the physics fine-tuning")
        ->capture_default_str()
        ->check(table_range("--physics-weight"));
    cmd->add_option("--physics-lr", args->physics_lr, "Adam learning rate of the physics fine-tuning")
        ->capture_default_str()
        ->check(table_range("--physics-lr"));
    cmd->callback([args] {
        check_output_path(args->output, "-o");
        if (!args->checkpoint.empty()) check_output_path(args->checkpoint, "--checkpoint");
        const Dataset data = load_dataset(args->data);
        AutoencoderOptions options;
        options.latent_dim = args->latent > 0 ? Index(args->latent) : default_latent_dim(data.scene_name);
        options.epochs = args->epochs;
        options.batch_size = args->batch;
        options.learning_rate = args->lr;
        options.pca_dim = Index(args->pca);
        options.hidden = parse_hidden_option(args->hidden);
        options.seed = args->seed;
        options.checkpoint_path = args->checkpoint;
        options.checkpoint_every = args->checkpoint_every;
        options.patience = args->patience;
        options.validation_fraction = args->validation;
        options.frame = parse_encoding_frame(args->frame);
        options.physics_epochs = args->physics_epochs;
        options.physics_weight = args->physics_weight;
        options.physics_learning_rate = args->physics_lr;
        options.progress = log_level() >= LogLevel::Info;

        Autoencoder ae(data.physics, options, options.seed);
        ae.set_scene_name(data.scene_name);
        const AutoencoderTrainSummary s = train_autoencoder(ae, data, options);
        ae.save(args->output, s.curves);
        std::printf("wrote %s: scene %s, %ld features -> latent %ld (pca %ld), %d epochs (best %d%s%s), "
                    "validation MSE %.4e m², validation relative RMSE %.4e, %.1f s\n",
                    args->output.c_str(), data.scene_name.c_str(), long(ae.num_features()), long(ae.latent_dim()),
                    long(ae.options().pca_dim), s.epochs_run, s.best_epoch, s.stopped_early ? ", stopped early" : "",
                    s.resumed ? ", resumed" : "", s.best_validation, s.validation_relative_rmse, s.seconds);
        if (s.physics_ran)
            std::printf("physics fine-tuning: %d epochs, L_recon %.4e -> %.4e m², L_ephys %.6g -> %.6g, %.1f s; "
                        "validation relative RMSE %.4e before it (held out); the validation frames are among "
                        "the frames it trains on\n",
                        s.physics_epochs_run, s.physics_recon_before, s.physics_recon_after, s.physics_ephys_before,
                        s.physics_ephys_after, s.physics_seconds, s.validation_relative_rmse_held_out);
    });
}

} // namespace lb::cli
