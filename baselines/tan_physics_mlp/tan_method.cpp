#include "baselines/tan_physics_mlp/tan_method.hpp"

#include <cmath>
#include <cstdio>

#include "baselines/tan_physics_mlp/tan_training.hpp"
#include "core/limits.hpp"
#include "core/log.hpp"
#include "core/parse.hpp"
#include "core/timer.hpp"
#include "eval/embedding_metrics.hpp"
#include "io/hdf5.hpp"
#include "paper/scene_defaults.hpp"

namespace lb {

namespace {

constexpr const char* kAutoencoderPrefix = "tan_ae.";
constexpr const char* kIntegratorPrefix = "integrator.";

class TanMethod final : public Method {
public:
    TanMethod(TanOptions options, bool hidden_given) : m_options(std::move(options)), m_hidden_given(hidden_given) { }

    std::string method_name() const override { return "tan_physics_mlp"; }
    void resolve(const MethodScene& scene) override
    {
        if (!m_hidden_given) m_options.hidden = default_integrator_hidden(scene.scene_name);
        m_hidden_given = true;
    }
    std::string options_text() const override
    {
        const TanOptions& o = m_options;
        toml::table t;
        t.insert_or_assign("stage1", o.stage1);
        t.insert_or_assign("stage2", o.stage2);
        t.insert_or_assign("stage3", o.stage3);
        t.insert_or_assign("lambda_recon", o.weights.recon);
        t.insert_or_assign("lambda_ephys", o.weights.ephys);
        t.insert_or_assign("lambda_sim", o.weights.sim);
        t.insert_or_assign("lambda_mphys", o.weights.mphys);
        t.insert_or_assign("window", (long long)o.window);
        t.insert_or_assign("stop_gradient", o.stop_gradient);
        toml::array hidden;
        for (Index w : o.hidden) hidden.push_back((long long)w);
        t.insert_or_assign("hidden", hidden);
        t.insert_or_assign("stage1_epochs", (long long)o.stage1_epochs);
        t.insert_or_assign("stage2_epochs", (long long)o.stage2_epochs);
        t.insert_or_assign("stage3_epochs", (long long)o.stage3_epochs);
        t.insert_or_assign("batch", (long long)o.batch_size);
        t.insert_or_assign("learning_rate", o.learning_rate);
        t.insert_or_assign("ae_learning_rate", o.ae_learning_rate);
        t.insert_or_assign("penalty_weight", o.penalty_weight);
        t.insert_or_assign("seed", (long long)o.seed);
        t.insert_or_assign("max_seconds", o.max_seconds);
        return to_toml_string(t);
    }
    std::string summary() const override
    {
        const TanOptions& o = m_options;
        std::string stages;
        for (int k = 0; k < 3; ++k) {
            if ((k == 0 && o.stage1) || (k == 1 && o.stage2) || (k == 2 && o.stage3))
                stages += (stages.empty() ? "" : "+") + std::to_string(k + 1);
        }
        char line[200];
        std::snprintf(line, sizeof line, "Tan et al. stages %s, λ recon/ephys/sim/mphys %g/%g/%g/%g, K = %ld%s",
                      stages.c_str(), o.weights.recon, o.weights.ephys, o.weights.sim, o.weights.mphys, long(o.window),
                      o.stop_gradient ? "" : ", no stop-gradient");
        return line;
    }
    std::string layers() const override { return format_list(m_options.hidden); }
    bool needs_autoencoder() const override { return true; }
    bool uses_weight_format() const override { return true; }
    bool set_seed(std::uint64_t seed) override
    {
        m_options.seed = seed;
        return true;
    }

    void fit(const MethodInputs& in, h5::File& out) const override
    {
        Timer timer;
        TanOptions o = m_options;
        o.progress = in.progress;
        o.checkpoint_path = in.checkpoint_path;
        o.resume = in.resume;
        const Dataset& data = *in.data;
        const PhysicsModel& model = *in.model;
        std::vector<EmbeddingMetrics> embeddings{embedding_metrics(*in.autoencoder, model, data, "shared autoencoder")};
        Autoencoder own = *in.autoencoder;  // the copy stages 1 and 3 fine-tune
        TanTrainer trainer(model, data, own, o);
        LatentMlpModel mlp = LatentMlpModel::create(own.latent_dim(), data.sequences.front().bc_params.cols(),
                                                    o.hidden, o.seed);
        mlp.loss = "tan_physics_mlp";
        mlp.description = summary();
        TanStageReport reports[3];
        if (o.stage1) {
            reports[0] = trainer.stage1();
            embeddings.push_back(embedding_metrics(own, model, data, "tan_physics_mlp after stage 1"));
        }
        if (o.stage2) reports[1] = trainer.stage2(mlp);
        if (o.stage3) {
            reports[2] = trainer.stage3(mlp);
            embeddings.push_back(embedding_metrics(own, model, data, "tan_physics_mlp after stage 3"));
        }
        own.save_into(out, kAutoencoderPrefix);
        mlp.save(out, kIntegratorPrefix);
        save_embedding_metrics(out, embeddings);

        long long epochs = 0, budget = 0;
        double seconds_trained = 0.0, seconds_before = 0.0;
        bool time_limited = false;
        const int budgets[3] = {o.stage1_epochs, o.stage2_epochs, o.stage3_epochs};
        nn::TrainingCurves curves;
        for (int k = 0; k < 3; ++k) {
            const TanStageReport& r = reports[k];
            const std::string p = "tan.stage" + std::to_string(k + 1) + ".";
            out.set_attribute("/", p + "ran", (long long)r.ran);
            if (!r.ran) continue;
            out.set_attribute("/", p + "loss_before", r.loss_before);
            out.set_attribute("/", p + "loss_after", r.loss_after);
            out.set_attribute("/", p + "recon", r.parts_after.recon);
            out.set_attribute("/", p + "ephys", r.parts_after.ephys);
            out.set_attribute("/", p + "sim", r.parts_after.sim);
            out.set_attribute("/", p + "mphys", r.parts_after.mphys);
            out.set_attribute("/", p + "epochs", (long long)r.loop.epochs_run);
            out.set_attribute("/", p + "seconds", r.loop.seconds);
            curves.push_back(r.loop.curve);
            curves.back().stage = "stage" + std::to_string(k + 1);
            epochs += r.loop.epochs_run;
            budget += budgets[k];
            seconds_trained += r.loop.seconds;
            seconds_before += r.loop.seconds_before;  // a resumed stage's earlier processes
            time_limited = time_limited || r.loop.time_limited;
        }
        out.set_attribute("/", "tan.window", (long long)trainer.window());
        // The budget attributes every learned method writes (the tables' "training" column):
        // epochs summed over the stages that ran; seconds with the set-up (metrics, copies) and
        // the earlier processes' training of resumed stages.
        out.set_attribute("/", "epochs_run", epochs);
        out.set_attribute("/", "epochs_budget", budget);
        const double seconds_in_all = seconds_before + timer.seconds();
        out.set_attribute("/", "train_seconds", seconds_in_all);
        out.set_attribute("/", "max_seconds", o.max_seconds);
        out.set_attribute("/", "time_limited", (long long)time_limited);
        out.set_attribute("/", "stopped_early", 0LL);
        // The loss per epoch of every stage that ran, and the last one's last loss.
        nn::save_training_curves(out, "", curves);
        if (const double last = nn::last_train_loss(curves); !std::isnan(last)) out.set_attribute("/", "final_loss", last);
        log_info("tan_physics_mlp: %lld epochs over the stages (%.1f s training, %.1f s in all), K = %ld", epochs,
                 seconds_trained, seconds_in_all, long(trainer.window()));
    }

    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        auto own = std::make_shared<Autoencoder>(Autoencoder::load_from(*artefact, kAutoencoderPrefix, in.model->spec()));
        return std::make_unique<LatentMlpIntegrator>(label, own, LatentMlpModel::load(*artefact, kIntegratorPrefix),
                                                     in.weights);
    }

private:
    TanOptions m_options;
    bool m_hidden_given = false;
};

double read_weight(ConfigTable& entry, const std::string& key, double fallback)
{
    const double v = entry.get_double(key, fallback);
    if (!(v >= 0.0) || !std::isfinite(v)) entry.fail(key, "must be a finite number ≥ 0");
    return v;
}

std::unique_ptr<Method> parse_tan(ConfigTable& entry, ConfigTable&)
{
    TanOptions o;
    bool hidden_given = false;
    o.stage1 = entry.get_bool("stage1", o.stage1);
    o.stage2 = entry.get_bool("stage2", o.stage2);
    o.stage3 = entry.get_bool("stage3", o.stage3);
    if (!o.stage2 && !o.stage3) entry.fail("stage2", "stage2 and stage3 are both off: the MLP would never be trained");
    o.weights.recon = read_weight(entry, "lambda_recon", o.weights.recon);
    o.weights.ephys = read_weight(entry, "lambda_ephys", o.weights.ephys);
    o.weights.sim = read_weight(entry, "lambda_sim", o.weights.sim);
    o.weights.mphys = read_weight(entry, "lambda_mphys", o.weights.mphys);
    if (o.stage2 && o.weights.sim == 0.0 && o.weights.mphys == 0.0)
        entry.fail("lambda_sim", "lambda_sim and lambda_mphys are both 0: stage 2 would have no loss");
    o.window = entry.get_int("window", o.window, 1, 1000);
    o.stop_gradient = entry.get_bool("stop_gradient", o.stop_gradient);
    if (entry.has("hidden")) {
        o.hidden = entry.get_widths("hidden", o.hidden);
        hidden_given = true;
    }
    o.stage1_epochs = entry.get_count("stage1_epochs", o.stage1_epochs, 0, kMaxEpochs);
    o.stage2_epochs = entry.get_count("stage2_epochs", o.stage2_epochs, 0, kMaxEpochs);
    o.stage3_epochs = entry.get_count("stage3_epochs", o.stage3_epochs, 0, kMaxEpochs);
    o.batch_size = entry.get_count("batch", int(o.batch_size), 1, kMaxBatch);
    o.learning_rate = entry.get_double("learning_rate", o.learning_rate);
    o.ae_learning_rate = entry.get_double("ae_learning_rate", o.ae_learning_rate);
    o.penalty_weight = entry.get_double("penalty_weight", o.penalty_weight);
    o.seed = std::uint64_t(entry.get_int("seed", (long long)o.seed, 0, kMaxSeed));
    o.max_seconds = entry.get_double("max_seconds", o.max_seconds);
    if (!(o.learning_rate > 0.0) || !std::isfinite(o.learning_rate)) entry.fail("learning_rate", "must be positive");
    if (!(o.ae_learning_rate > 0.0) || !std::isfinite(o.ae_learning_rate))
        entry.fail("ae_learning_rate", "must be positive");
    if (!(o.penalty_weight > 0.0) || !std::isfinite(o.penalty_weight)) entry.fail("penalty_weight", "must be positive");
    if (!(o.max_seconds >= 0.0)) entry.fail("max_seconds", "must be non-negative");
    entry.finish();
    return std::make_unique<TanMethod>(o, hidden_given);
}

} // namespace

MethodFactory tan_physics_mlp_method()
{
    MethodFactory f;
    f.name = "tan_physics_mlp";
    f.description = "baseline (Tan et al.): z_m = MLP(z_{m-2}, z_{m-1}, q_m) with physics losses on its own fine-tuned "
                    "autoencoder, three stages (embedding; MLP with stopped-gradient unrolled physics; joint)";
    f.parse = parse_tan;
    f.quick_options = "stage1_epochs = 2\nstage2_epochs = 2\nstage3_epochs = 2\nwindow = 3\nbatch = 32\nhidden = [16]\n";
    return f;
}

} // namespace lb
