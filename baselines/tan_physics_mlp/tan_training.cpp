#include "baselines/tan_physics_mlp/tan_training.hpp"

#include <algorithm>
#include <functional>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/log.hpp"
#include "integrators/trainer.hpp"
#include "nn/checkpoint.hpp"

namespace lb {

namespace {

/// Samples per chunk when a stage's loss is evaluated over all its samples.
constexpr Index kEvaluationChunk = 256;

} // namespace

std::string TanOptions::describe() const
{
    std::ostringstream s;
    s << "stages=" << stage1 << stage2 << stage3 << ";recon=" << nn::exact_text(weights.recon)
      << ";ephys=" << nn::exact_text(weights.ephys) << ";sim=" << nn::exact_text(weights.sim)
      << ";mphys=" << nn::exact_text(weights.mphys) << ";window=" << window << ";stop_gradient=" << stop_gradient
      << ";hidden=";
    for (size_t i = 0; i < hidden.size(); ++i) s << (i ? "," : "") << hidden[i];
    s << ";epochs=" << stage1_epochs << "," << stage2_epochs << "," << stage3_epochs << ";batch=" << batch_size
      << ";lr=" << nn::exact_text(learning_rate) << ";ae_lr=" << nn::exact_text(ae_learning_rate)
      << ";penalty_weight=" << nn::exact_text(penalty_weight) << ";seed=" << seed
      << ";max_seconds=" << nn::exact_text(max_seconds);
    return s.str();
}

TanTrainer::TanTrainer(const PhysicsModel& model, const Dataset& data, Autoencoder& ae, TanOptions options)
    : m_model(model), m_data(data), m_ae(ae), m_options(std::move(options)),
      m_losses(model, data, ae, m_options.penalty_weight)
{
    m_window = std::min(m_options.window, m_losses.max_window());
    if (m_window < 1) throw ConfigError("tan_physics_mlp: every sequence needs at least 3 training frames");
    if (m_window < m_options.window)
        log_info("tan_physics_mlp: window clamped from %ld to %ld steps (the shortest training sequence)",
                 long(m_options.window), long(m_window));
}

std::string TanTrainer::checkpoint_for(int stage) const
{
    if (m_options.checkpoint_path.empty()) return "";
    return m_options.checkpoint_path + ".stage" + std::to_string(stage);
}

nn::Fingerprint TanTrainer::fingerprint(int stage, LatentMlpModel* mlp)
{
    Fnv1a64 data, net;
    for (const TanSequence& s : m_losses.sequences()) data.add(s.X).add(s.targets).add(s.params);
    if (mlp) {
        nn::hash_network(net, mlp->network);
        net.add(mlp->inputs.mean()).add(mlp->inputs.stddev()).add(mlp->output_scale);
    }
    nn::Fingerprint f;
    f.add("options", "stage=" + std::to_string(stage) + ";window_used=" + std::to_string(m_window) + ";" +
                         m_options.describe())
        .add("autoencoder", m_ae.content_hash())
        .add("data", data.hex())
        .add("physics", physics_content_hash(m_model.spec()))
        .add("network", net.hex());
    return f;
}

void TanTrainer::fit_mlp_statistics(LatentMlpModel& mlp)
{
    fit_input_statistics(mlp, make_training_samples(m_ae, m_data));
    m_statistics_fitted = true;
}

double TanTrainer::stage_loss(int stage, LatentMlpModel* mlp, TanLossParts& parts)
{
    const std::vector<TanSample> all = stage == 2 ? m_losses.window_samples(m_window) : m_losses.frame_samples();
    if ((stage == 2 || stage == 3) && !mlp) throw Error("TanTrainer::stage_loss: stages 2 and 3 need the MLP");
    double loss = 0.0;
    parts = TanLossParts{};
    const Index S = Index(all.size());
    for (Index begin = 0; begin < S; begin += kEvaluationChunk) {
        const Index end = std::min(S, begin + kEvaluationChunk);
        const std::vector<TanSample> chunk(all.begin() + begin, all.begin() + end);
        TanLossParts p;
        double l = 0.0;
        if (stage == 1) l = m_losses.embedding_loss(chunk, m_options.weights, false, &p);
        else if (stage == 2) l = m_losses.mlp_loss(*mlp, chunk, m_window, m_options.weights, m_options.stop_gradient, false, &p);
        else l = m_losses.joint_loss(*mlp, chunk, m_options.weights, false, &p);
        const double f = double(end - begin) / double(S);
        loss += f * l;
        parts.recon += f * p.recon;
        parts.ephys += f * p.ephys;
        parts.sim += f * p.sim;
        parts.mphys += f * p.mphys;
    }
    return loss;
}

namespace {

nn::TrainingLoopOptions loop_options(const TanOptions& o, int stage, int epochs, double lr, std::string checkpoint)
{
    nn::TrainingLoopOptions loop;
    static_cast<nn::TrainingRunOptions&>(loop) = o;
    loop.checkpoint_path = std::move(checkpoint);
    loop.label = "tan stage " + std::to_string(stage);
    loop.trainer = "tan_physics_mlp stage " + std::to_string(stage);
    loop.epochs = epochs;
    loop.batch_size = o.batch_size;
    loop.learning_rate = lr;
    loop.seed = o.seed + std::uint64_t(stage);
    return loop;
}

void log_stage(int stage, const TanStageReport& r)
{
    log_info("tan_physics_mlp stage %d: loss %.6g -> %.6g (recon %.4g -> %.4g, ephys %.4g -> %.4g, sim %.4g -> %.4g, "
             "mphys %.4g -> %.4g), %d epochs, %.1f s%s",
             stage, r.loss_before, r.loss_after, r.parts_before.recon, r.parts_after.recon, r.parts_before.ephys,
             r.parts_after.ephys, r.parts_before.sim, r.parts_after.sim, r.parts_before.mphys, r.parts_after.mphys,
             r.loop.epochs_run, r.loop.seconds, r.loop.time_limited ? " (time limit)" : "");
}

} // namespace

TanStageReport TanTrainer::run_stage(int stage, LatentMlpModel* mlp, std::vector<TanSample> samples,
                                     std::vector<nn::ParameterRef> parameters, int epochs, double learning_rate,
                                     const std::function<double(const std::vector<TanSample>&)>& loss)
{
    TanStageReport r;
    r.ran = true;
    r.loss_before = stage_loss(stage, mlp, r.parts_before);
    const nn::Fingerprint print = fingerprint(stage, mlp);
    FrameSampleLearner learner(std::move(samples), std::move(parameters), loss);
    r.loop = nn::run_training_loop(learner, loop_options(m_options, stage, epochs, learning_rate, checkpoint_for(stage)),
                                   print);
    r.loss_after = stage_loss(stage, mlp, r.parts_after);
    log_stage(stage, r);
    return r;
}

TanStageReport TanTrainer::stage1()
{
    return run_stage(1, nullptr, m_losses.frame_samples(), autoencoder_parameters(m_ae, "tan_ae."), m_options.stage1_epochs,
                     m_options.ae_learning_rate, [&](const std::vector<TanSample>& b) {
                         return m_losses.embedding_loss(b, m_options.weights, true);
                     });
}

TanStageReport TanTrainer::stage2(LatentMlpModel& mlp)
{
    if (!m_statistics_fitted) fit_mlp_statistics(mlp);
    return run_stage(2, &mlp, m_losses.window_samples(m_window), mlp.network.parameters("integrator."),
                     m_options.stage2_epochs, m_options.learning_rate, [&](const std::vector<TanSample>& b) {
                         return m_losses.mlp_loss(mlp, b, m_window, m_options.weights, m_options.stop_gradient, true);
                     });
}

TanStageReport TanTrainer::stage3(LatentMlpModel& mlp)
{
    if (!m_statistics_fitted) fit_mlp_statistics(mlp);
    std::vector<nn::ParameterRef> params = autoencoder_parameters(m_ae, "tan_ae.");
    for (auto& p : mlp.network.parameters("integrator.")) params.push_back(p);
    return run_stage(3, &mlp, m_losses.frame_samples(), std::move(params), m_options.stage3_epochs,
                     m_options.ae_learning_rate,
                     [&](const std::vector<TanSample>& b) { return m_losses.joint_loss(mlp, b, m_options.weights, true); });
}

} // namespace lb
