#include "methods/latent_mlp/latent_mlp_method.hpp"

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parse.hpp"
#include "integrators/trainer.hpp"
#include "io/hdf5.hpp"
#include "paper/scene_defaults.hpp"

namespace lb {

namespace {

/// An enumerated key: `parse` (an `<enum>_from_string`) reads its text, and its ConfigError
/// (naming the accepted values) is reported against the key.
template <typename Enum>
Enum get_choice(ConfigTable& t, const std::string& key, Enum fallback, Enum (*parse)(const std::string&))
{
    const std::string text = t.get_string(key, to_string(fallback));
    try {
        return parse(text);
    } catch (const ConfigError& e) {
        t.fail(key, e.what());
    }
}

/// The training keys, valid in [training], [scenes.training] and the entry itself.
void read_training(ConfigTable& t, IntegratorTrainOptions& o, bool& hidden_given)
{
    if (t.has("hidden")) {
        o.hidden = t.get_widths("hidden", o.hidden);
        hidden_given = true;
    }
    o.epochs = t.get_count("epochs", o.epochs, 1, kMaxEpochs);
    o.batch_size = t.get_count("batch", o.batch_size, 1, kMaxBatch);
    o.learning_rate = t.get_double("learning_rate", o.learning_rate);
    o.max_seconds = t.get_double("max_seconds", o.max_seconds);
    o.noise_fraction = t.get_double("noise_fraction", o.noise_fraction);
    o.noise_draw = get_choice(t, "noise_draw", o.noise_draw, noise_draw_from_string);
    o.balancing_floor = t.get_double("balancing_floor", o.balancing_floor);
    o.balancing_velocity = get_choice(t, "balancing_velocity", o.balancing_velocity, balancing_velocity_from_string);
    o.penalty_weight = t.get_double("penalty_weight", o.penalty_weight);
    o.overwrite_dirichlet = t.get_bool("overwrite_dirichlet", o.overwrite_dirichlet);
    o.float32_decoder = t.get_bool("float32_decoder", o.float32_decoder);
    o.boundary_input = get_choice(t, "boundary_input", o.boundary_input, boundary_input_from_string);
    o.seed = std::uint64_t(t.get_int("seed", (long long)o.seed, 0, kMaxSeed));
    if (o.epochs < 1) t.fail("epochs", "must be at least 1");
    if (o.batch_size < 1) t.fail("batch", "must be at least 1");
    if (!(o.learning_rate > 0.0)) t.fail("learning_rate", "must be positive");
    if (o.max_seconds < 0.0) t.fail("max_seconds", "must be non-negative");
    if (o.noise_fraction < 0.0) t.fail("noise_fraction", "must be non-negative");
    if (!(o.balancing_floor >= 0.0)) t.fail("balancing_floor", "must be non-negative");
    if (!(o.penalty_weight > 0.0)) t.fail("penalty_weight", "must be positive");
}

class LatentMlpMethod final : public Method {
public:
    LatentMlpMethod(IntegratorTrainOptions options, bool hidden_given)
        : m_options(std::move(options)), m_hidden_given(hidden_given)
    {
    }

    std::string method_name() const override { return "latent_mlp"; }

    void resolve(const MethodScene& scene) override
    {
        if (!m_hidden_given) m_options.hidden = default_integrator_hidden(scene.scene_name);
        m_hidden_given = true;
    }

    /// 2 (2026-11-30): every sample every epoch and the compiled frozen decoder
    /// (integrators/trainer.cpp); version-1 artefacts dropped each epoch's partial batch.
    int fit_version() const override { return 2; }
    std::string options_text() const override
    {
        const IntegratorTrainOptions& o = m_options;
        toml::table t;
        t.insert_or_assign("loss", to_string(o.loss));
        toml::array hidden;
        for (Index w : o.hidden) hidden.push_back((long long)w);
        t.insert_or_assign("hidden", hidden);
        t.insert_or_assign("epochs", (long long)o.epochs);
        t.insert_or_assign("batch", (long long)o.batch_size);
        t.insert_or_assign("learning_rate", o.learning_rate);
        t.insert_or_assign("noise", o.training_noise);
        t.insert_or_assign("noise_fraction", o.noise_fraction);
        // Only when not the default: the text is the cache key of fits made before the option.
        if (o.training_noise && o.noise_draw != NoiseDraw::Independent)
            t.insert_or_assign("noise_draw", to_string(o.noise_draw));
        if (o.loss == IntegratorLoss::SelfSupervised) {  // the supervised loss has no balancing
            t.insert_or_assign("balancing", o.data_balancing);
            t.insert_or_assign("balancing_floor", o.balancing_floor);
            // Only when not the default: the text is the cache key of fits made before the option.
            if (o.data_balancing && o.balancing_velocity != BalancingVelocity::MeanVelocity)
                t.insert_or_assign("balancing_velocity", to_string(o.balancing_velocity));
        }
        t.insert_or_assign("penalty_weight", o.penalty_weight);
        if (o.overwrite_dirichlet) t.insert_or_assign("overwrite_dirichlet", true);  // only when on: earlier keys stay
        if (o.float32_decoder && o.loss == IntegratorLoss::SelfSupervised)  // only that loss decodes while training
            t.insert_or_assign("float32_decoder", true);
        if (o.boundary_input != BoundaryInputKind::Velocity) t.insert_or_assign("boundary_input", to_string(o.boundary_input));
        t.insert_or_assign("seed", (long long)o.seed);
        t.insert_or_assign("max_seconds", o.max_seconds);
        return to_toml_string(t);
    }

    std::string summary() const override
    {
        if (m_options.loss == IntegratorLoss::SupervisedL2)
            return (m_options.training_noise ? "supervised_l2 + noise" : "supervised_l2") +
                   m_options.representation_text();
        return to_string(m_options.loss) + ", noise " + (m_options.training_noise ? "on" : "off") + ", " +
               m_options.balancing_text() + m_options.representation_text();
    }
    std::string layers() const override { return format_list(m_options.hidden); }
    bool needs_autoencoder() const override { return true; }
    bool uses_weight_format() const override { return true; }
    bool is_paper_method() const override { return m_options.loss == IntegratorLoss::SelfSupervised; }
    bool set_seed(std::uint64_t seed) override
    {
        m_options.seed = seed;
        return true;
    }

    void fit(const MethodInputs& in, h5::File& out) const override
    {
        IntegratorTrainOptions o = m_options;
        o.progress = in.progress;
        o.checkpoint_path = in.checkpoint_path;
        o.resume = in.resume;
        Autoencoder& ae = *in.autoencoder;
        IntegratorTrainer trainer(*in.model, ae, o);
        const TrainingSamples samples = make_training_samples(ae, *in.data, trainer.boundary_input());
        log_info("training latent_mlp (%s) on %ld samples", o.describe().c_str(), long(samples.size()));
        LatentMlpModel net = LatentMlpModel::create(ae.latent_dim(), samples.p.rows(), o.hidden, o.seed);
        const IntegratorTrainSummary s = trainer.train(net, samples);
        net.save(out, "integrator.");
        out.set_attribute("/", "epochs_run", (long long)s.epochs_run);
        out.set_attribute("/", "final_loss", s.final_loss);
        nn::TrainingCurve curve = s.curve;
        curve.stage = "integrator";
        nn::save_training_curves(out, "", {curve});
        out.set_attribute("/", "train_seconds", s.seconds);
        out.set_attribute("/", "resumed", (long long)s.resumed);
        // The training budget and how the run ended (the tables state them).
        out.set_attribute("/", "epochs_budget", (long long)o.epochs);
        out.set_attribute("/", "max_seconds", o.max_seconds);
        out.set_attribute("/", "time_limited", (long long)s.time_limited);
        out.set_attribute("/", "stopped_early", (long long)s.stopped_early);
        log_info("latent_mlp: %d epochs, final loss %.6g, %.1f s%s%s", s.epochs_run, s.final_loss, s.seconds,
                 s.resumed ? " (resumed from a checkpoint)" : "", s.time_limited ? " (time limit)" : "");
    }

    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        return std::make_unique<LatentMlpIntegrator>(label, in.autoencoder, LatentMlpModel::load(*artefact, "integrator."),
                                                     in.weights);
    }

private:
    IntegratorTrainOptions m_options;
    bool m_hidden_given = false;
};

std::unique_ptr<Method> parse_latent_mlp(ConfigTable& entry, ConfigTable& defaults)
{
    IntegratorTrainOptions o;
    bool hidden_given = false;
    read_training(defaults, o, hidden_given);
    const std::string loss = entry.get_string("loss", to_string(o.loss));
    if (loss != "self_supervised" && loss != "supervised_l2")
        entry.fail("loss", "unknown loss '" + loss + "' (self_supervised or supervised_l2)");
    o.loss = integrator_loss_from_string(loss);
    // The paper's supervised baseline differs from its method only in the loss: no
    // training noise unless asked for ("supervised + noise", a variant of its own), and
    // no data balancing, which the supervised loss does not use.
    const bool supervised = o.loss == IntegratorLoss::SupervisedL2;
    o.training_noise = entry.get_bool("noise", supervised ? false : o.training_noise);
    o.data_balancing = entry.get_bool("balancing", o.data_balancing);
    if (supervised) {
        // Accepted (artefacts written before this rule carry it) but meaningless: dropped.
        if (entry.has("balancing") && o.data_balancing)
            log_warn("latent_mlp: 'balancing' applies to the self-supervised loss only; supervised_l2 ignores it");
        o.data_balancing = false;
    }
    read_training(entry, o, hidden_given);
    entry.finish();
    return std::make_unique<LatentMlpMethod>(o, hidden_given);
}

} // namespace

MethodFactory latent_mlp_method()
{
    MethodFactory f;
    f.name = "latent_mlp";
    f.description = "Li et al. 2025: an MLP integrator in the autoencoder's latent space (loss = self_supervised | "
                    "supervised_l2; the supervised baseline trains without noise unless noise = true)";
    f.parse = parse_latent_mlp;
    f.quick_options = "epochs = 3\nbatch = 64\nhidden = [16]\nlearning_rate = 1.0e-3\n";
    return f;
}

} // namespace lb
