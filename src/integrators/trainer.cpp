#include "integrators/trainer.hpp"

#include <algorithm>
#include <cassert>
#include <filesystem>
#include <numeric>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "energy/inertia_energy.hpp"
#include "io/hdf5.hpp"
#include "nn/adam.hpp"
#include "nn/checkpoint.hpp"
#include "nn/training_loop.hpp"
#include "nn/serialization.hpp"

namespace lb {

std::string to_string(IntegratorLoss loss)
{
    return loss == IntegratorLoss::SelfSupervised ? "self_supervised" : "supervised_l2";
}

IntegratorLoss integrator_loss_from_string(const std::string& name)
{
    if (name == "self_supervised") return IntegratorLoss::SelfSupervised;
    if (name == "supervised_l2") return IntegratorLoss::SupervisedL2;
    throw ConfigError("unknown integrator loss '" + name + "' (expected self_supervised or supervised_l2)");
}

std::string to_string(BalancingVelocity velocity)
{
    return velocity == BalancingVelocity::MeanVelocity ? "mean_velocity" : "mean_speed";
}

BalancingVelocity balancing_velocity_from_string(const std::string& name)
{
    if (name == "mean_velocity") return BalancingVelocity::MeanVelocity;
    if (name == "mean_speed") return BalancingVelocity::MeanSpeed;
    throw ConfigError("unknown balancing velocity '" + name + "' (expected mean_velocity or mean_speed)");
}

void balancing_speeds(const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2, double dt,
                      BalancingVelocity velocity, Eigen::Ref<VectorXd> speeds)
{
    assert(X_prev.rows() == X_prev2.rows() && X_prev.cols() == X_prev2.cols() && X_prev.rows() % 3 == 0);
    assert(speeds.size() == X_prev.cols());
    const Index N = X_prev.rows() / 3;
    parallel_for(X_prev.cols(), X_prev.cols() >= kParallelColumns, [&](Index i) {
        // Displacements over h of the N vertices, read in place (no per-column copy).
        Vector3d mean_velocity = Vector3d::Zero();
        double mean_speed = 0.0;
        for (Index j = 0; j < N; ++j) {
            const Vector3d d = X_prev.col(i).segment<3>(3 * j) - X_prev2.col(i).segment<3>(3 * j);
            mean_velocity += d;
            mean_speed += d.norm();
        }
        speeds[i] = velocity == BalancingVelocity::MeanVelocity ? (mean_velocity / double(N) / dt).norm()
                                                                : mean_speed / double(N) / dt;
    });
}

VectorXd balancing_speeds(const Eigen::Ref<const MatrixXd>& X_prev, const Eigen::Ref<const MatrixXd>& X_prev2,
                          double dt, BalancingVelocity velocity)
{
    VectorXd speeds(X_prev.cols());
    balancing_speeds(X_prev, X_prev2, dt, velocity, speeds);
    return speeds;
}

std::string IntegratorTrainOptions::balancing_text() const
{
    if (!data_balancing) return "balancing off";
    return balancing_velocity == BalancingVelocity::MeanSpeed ? "balancing on (mean speed)" : "balancing on";
}

std::string IntegratorTrainOptions::representation_text() const
{
    std::string s = overwrite_dirichlet ? ", Dirichlet overwritten" : "";
    if (boundary_input == BoundaryInputKind::Pose) s += ", boundary pose in p";
    if (float32_decoder && loss == IntegratorLoss::SelfSupervised) s += ", float32 decoder";  // the only loss that decodes
    return s;
}

std::string to_string(NoiseDraw draw) { return draw == NoiseDraw::Shared ? "shared" : "independent"; }

NoiseDraw noise_draw_from_string(const std::string& name)
{
    if (name == "independent") return NoiseDraw::Independent;
    if (name == "shared") return NoiseDraw::Shared;
    throw ConfigError("unknown noise draw '" + name + "' (independent or shared)");
}

std::string IntegratorTrainOptions::describe() const
{
    std::ostringstream s;
    s << to_string(loss) << ", hidden [";
    for (size_t i = 0; i < hidden.size(); ++i) s << (i ? "," : "") << hidden[i];
    s << "], noise " << (training_noise ? "on" : "off");
    if (loss == IntegratorLoss::SelfSupervised) s << ", " << balancing_text();
    s << representation_text() << ", lr " << learning_rate << ", batch " << batch_size << ", seed " << seed;
    return s.str();
}

std::string IntegratorTrainer::resolved_options(Index num_samples) const
{
    const IntegratorTrainOptions& o = m_options;
    const bool self_supervised = o.loss == IntegratorLoss::SelfSupervised;
    std::ostringstream s;
    s << "loss=" << to_string(o.loss) << ";hidden=";
    for (size_t i = 0; i < o.hidden.size(); ++i) s << (i ? "," : "") << o.hidden[i];
    s << ";epochs=" << o.epochs << ";batch=" << std::min<Index>(o.batch_size, num_samples)
      << ";lr=" << nn::exact_text(o.learning_rate) << ";noise=" << (o.training_noise ? "on" : "off");
    if (o.training_noise) s << ";noise_fraction=" << nn::exact_text(o.noise_fraction);
    if (o.training_noise && o.noise_draw != NoiseDraw::Independent) s << ";noise_draw=" << to_string(o.noise_draw);
    if (self_supervised) {
        s << ";balancing=" << (o.data_balancing ? "on" : "off");
        if (o.data_balancing) s << ";balancing_floor=" << nn::exact_text(o.balancing_floor);
        // Only when not the default, so fits made before the option keep their fingerprints.
        if (o.data_balancing && o.balancing_velocity != BalancingVelocity::MeanVelocity)
            s << ";balancing_velocity=" << to_string(o.balancing_velocity);
        s << ";penalty_weight=" << nn::exact_text(m_potential.penalty_weight());
    }
    // Representation switches (issue 14), only when on: the fingerprints of earlier fits stay.
    if (o.overwrite_dirichlet) s << ";overwrite_dirichlet=on";
    if (o.boundary_input != BoundaryInputKind::Velocity) s << ";boundary_input=" << to_string(o.boundary_input);
    s << ";seed=" << o.seed << ";max_seconds=" << nn::exact_text(o.max_seconds);
    // Trainer generation 2 (2026-11-30): every sample every epoch, the compiled frozen
    // decoder. Runs of generation 1 (the last partial batch dropped) are not resumed.
    s << ";batches=all;decoder=compiled" << (o.float32_decoder ? "_float32" : "");
    return s.str();
}

TrainingSamples make_training_samples(Autoencoder& ae, const Dataset& data, const BoundaryInput& boundary)
{
    Index total = 0;
    for (const auto& s : data.sequences) total += std::max<Index>(s.train_frames - 2, 0);
    if (total == 0) throw Error("dataset has no training samples (every sequence needs train_frames ≥ 3)");
    const Index L = ae.latent_dim();
    const Index P = boundary.size(data.sequences.front().bc_params.cols());
    const Index B3 = data.sequences.front().bc_positions.cols();
    TrainingSamples out;
    out.boundary_input = boundary.kind();
    out.z_prev.resize(L, total);
    out.z_prev2.resize(L, total);
    out.z_target.resize(L, total);
    out.p.resize(P, total);
    out.p_prev.resize(P, total);
    out.p_prev2.resize(P, total);
    out.targets.resize(B3, total);
    out.targets_prev.resize(B3, total);
    out.targets_prev2.resize(B3, total);
    Index k = 0;
    for (const auto& s : data.sequences) {
        if (s.train_frames < 3) continue;
        const MatrixXd Z = ae.encode(s.positions.topRows(s.train_frames).transpose());
        for (Index t = 2; t < s.train_frames; ++t, ++k) {
            out.z_prev.col(k) = Z.col(t - 1);
            out.z_prev2.col(k) = Z.col(t - 2);
            out.z_target.col(k) = Z.col(t);
            auto p_of = [&](Index frame) {
                return boundary.of_frame(s.bc_params.row(frame).transpose(), s.bc_positions.row(frame).transpose());
            };
            out.p.col(k) = p_of(t);
            out.p_prev.col(k) = p_of(t - 1);
            out.p_prev2.col(k) = p_of(t - 2);
            out.targets.col(k) = s.bc_positions.row(t).transpose();
            out.targets_prev.col(k) = s.bc_positions.row(t - 1).transpose();
            out.targets_prev2.col(k) = s.bc_positions.row(t - 2).transpose();
        }
    }
    return out;
}

IntegratorTrainer::IntegratorTrainer(const PhysicsModel& model, Autoencoder& autoencoder,
                                     IntegratorTrainOptions options)
    : m_model(model),
      m_autoencoder(autoencoder),
      m_options(std::move(options)),
      m_potential(model, autoencoder, m_options.penalty_weight, m_options.overwrite_dirichlet)
{
}

IntegratorBatch IntegratorTrainer::make_batch(const TrainingSamples& samples, const std::vector<Index>& indices,
                                              Rng& rng) const
{
    IntegratorBatch b;
    make_batch(samples, indices, rng, b);
    return b;
}

void IntegratorTrainer::make_batch(const TrainingSamples& samples, const std::vector<Index>& indices, Rng& rng,
                                   IntegratorBatch& b) const
{
    const Index n = Index(indices.size());
    const Index copies = m_options.training_noise ? 2 : 1;
    const Index L = samples.z_prev.rows(), P = samples.p.rows();
    b.clean = n;
    b.source.clear();
    for (Index c = 0; c < copies; ++c) b.source.insert(b.source.end(), indices.begin(), indices.end());
    auto gather = [&](const MatrixXd& src, auto&& dst) {
        for (Index c = 0; c < copies; ++c) {
            for (Index i = 0; i < n; ++i) dst.col(c * n + i) = src.col(indices[size_t(i)]);
        }
    };
    auto gather_into = [&](const MatrixXd& src, nn::GrowingMatrix<double>& dst) {
        gather(src, dst.resize(src.rows(), n * copies));
    };
    gather_into(samples.z_prev, b.m_z_prev);
    gather_into(samples.z_prev2, b.m_z_prev2);
    gather_into(samples.z_target, b.m_z_target);
    gather_into(samples.targets, b.m_targets);
    gather_into(samples.targets_prev, b.m_targets_prev);
    gather_into(samples.targets_prev2, b.m_targets_prev2);
    Eigen::Map<MatrixXd> inputs = b.m_inputs.resize(2 * L + 3 * P, n * copies);
    gather(samples.p, inputs.middleRows(2 * L, P));
    gather(samples.p_prev, inputs.middleRows(2 * L + P, P));
    gather(samples.p_prev2, inputs.middleRows(2 * L + 2 * P, P));
    if (copies == 2) {
        // Uniform noise of noise_fraction × the batch's per-component std on the
        // second copy's input latents; boundary parameters unchanged.
        // With NoiseDraw::Shared the first latent's draws are kept and reused for the second.
        const bool shared = m_options.noise_draw == NoiseDraw::Shared;
        if (shared && (b.m_draw.rows() != L || b.m_draw.cols() < n)) b.m_draw.resize(L, std::max(n, b.m_draw.cols()));
        bool first = true;
        for (nn::GrowingMatrix<double>* buffer : {&b.m_z_prev, &b.m_z_prev2}) {
            Eigen::Map<MatrixXd> z = buffer->view();
            const auto clean = z.leftCols(n);
            b.m_mean = clean.rowwise().mean();
            b.m_std = ((clean.colwise() - b.m_mean).array().square().rowwise().sum() / double(n)).sqrt();
            for (Index i = 0; i < n; ++i) {
                for (Index c = 0; c < L; ++c) {
                    double u;
                    if (!shared) {
                        u = rng.uniform(-1.0, 1.0);
                    } else if (first) {
                        u = b.m_draw(c, i) = rng.uniform(-1.0, 1.0);
                    } else {
                        u = b.m_draw(c, i);
                    }
                    z(c, n + i) += m_options.noise_fraction * b.m_std[c] * u;
                }
            }
            first = false;
        }
    }
    inputs.topRows(L) = b.z_prev();
    inputs.middleRows(L, L) = b.z_prev2();
}

double IntegratorTrainer::evaluate(LatentMlpModel& model, const IntegratorBatch& batch, bool with_gradient)
{
    const Index B = batch.size();
    const nn::BatchView Zt = model.forward(batch.inputs(), batch.z_prev(), with_gradient);
    if (m_options.loss == IntegratorLoss::SupervisedL2) {
        auto diff = m_difference.resize(Zt.rows(), B);
        diff = Zt - batch.z_target();
        if (with_gradient) {
            auto dZ = m_latent_adjoint.resize(Zt.rows(), B);
            dZ = 2.0 * diff / double(B);
            model.backward(dZ);
        }
        return diff.squaredNorm() / double(B);
    }

    // Self-supervised: the incremental potential of the decoded prediction, each sample
    // weighted by data balancing, averaged over the batch.
    step_inputs(batch);
    auto weights = m_weights.resize(m_options.data_balancing ? B : 0, 1).col(0);  // empty: every w_i = 1
    if (m_options.data_balancing) weights_of(m_speeds.view().col(0), weights);
    auto grad_z = m_latent_adjoint.resize(with_gradient ? Zt.rows() : 0, with_gradient ? B : 0);
    const double objective = m_potential.objective_tilde(Zt, batch.targets(), m_x_tilde.view(), weights, double(B),
                                                         with_gradient, grad_z);
    if (with_gradient) model.backward(grad_z);
    return objective;
}

void IntegratorTrainer::cache_decoded_inputs(const TrainingSamples& samples)
{
    const MatrixXd X1 = m_potential.decode(samples.z_prev, samples.targets_prev);
    const MatrixXd X2 = m_potential.decode(samples.z_prev2, samples.targets_prev2);
    m_cached_tilde = inertial_target(X1, X2);
    m_cached_speeds = balancing_speeds(X1, X2, m_model.dt(), m_options.balancing_velocity);
}

void IntegratorTrainer::step_inputs(const IntegratorBatch& batch)
{
    const Index B = batch.size();
    const bool from_cache = m_cached_tilde.size() != 0 && batch.source.size() == size_t(B);
    const Index clean = from_cache ? batch.clean : 0;
    Eigen::Map<MatrixXd> X_tilde = m_x_tilde.resize(m_model.num_dofs(), B);
    auto speeds = m_speeds.resize(m_options.data_balancing ? B : 0, 1).col(0);
    parallel_for(clean, clean >= kParallelColumns, [&](Index i) {
        X_tilde.col(i) = m_cached_tilde.col(batch.source[size_t(i)]);
        if (speeds.size() != 0) speeds[i] = m_cached_speeds[batch.source[size_t(i)]];
    });
    const Index decoded = B - clean;
    if (decoded == 0) return;
    // One decoder pass per step, not one over both: the GEMMs' column blocks (and with them
    // the round-off of the columns at a block's edge) stay those the published fits had.
    Eigen::Map<MatrixXd> X1 = m_x_prev.resize(m_model.num_dofs(), decoded);
    Eigen::Map<MatrixXd> X2 = m_x_prev2.resize(m_model.num_dofs(), decoded);
    m_potential.decode(batch.z_prev().rightCols(decoded), batch.targets_prev().rightCols(decoded), X1);
    m_potential.decode(batch.z_prev2().rightCols(decoded), batch.targets_prev2().rightCols(decoded), X2);
    X_tilde.rightCols(decoded) = inertial_target(X1, X2);
    if (speeds.size() != 0)
        balancing_speeds(X1, X2, m_model.dt(), m_options.balancing_velocity, speeds.tail(decoded));
}

double IntegratorTrainer::loss_and_gradient(LatentMlpModel& model, const IntegratorBatch& batch)
{
    return evaluate(model, batch, true);
}

double IntegratorTrainer::loss(LatentMlpModel& model, const IntegratorBatch& batch)
{
    return evaluate(model, batch, false);
}

double IntegratorTrainer::mean_input_speed(const TrainingSamples& samples)
{
    if (m_cached_speeds.size() != samples.size()) cache_decoded_inputs(samples);
    return m_cached_speeds.mean();
}

VectorXd IntegratorTrainer::balancing_weights(const Eigen::Ref<const MatrixXd>& X_prev,
                                             const Eigen::Ref<const MatrixXd>& X_prev2) const
{
    return weights_of(balancing_speeds(X_prev, X_prev2, m_model.dt(), m_options.balancing_velocity));
}

VectorXd IntegratorTrainer::weights_of(const Eigen::Ref<const VectorXd>& speeds) const
{
    VectorXd weights(speeds.size());
    weights_of(speeds, weights);
    return weights;
}

void IntegratorTrainer::weights_of(const Eigen::Ref<const VectorXd>& speeds, Eigen::Ref<VectorXd> weights) const
{
    weights = speeds.unaryExpr([&](double v) { return 1.0 / std::max(v, m_velocity_floor); });
}

namespace {

std::string samples_hash(const TrainingSamples& s)
{
    Fnv1a64 h;
    for (const MatrixXd* m : {&s.z_prev, &s.z_prev2, &s.z_target, &s.p, &s.p_prev, &s.p_prev2, &s.targets,
                              &s.targets_prev, &s.targets_prev2})
        h.add(*m);
    return h.hex();
}

/// The integrator as seen by the shared training loop: batches (with noise) from the
/// samples, the trainer's loss and gradient.
class IntegratorLearner final : public nn::Learner {
public:
    IntegratorLearner(IntegratorTrainer& trainer, LatentMlpModel& model, const TrainingSamples& samples)
        : m_trainer(trainer), m_model(model), m_samples(samples)
    {
    }
    Index num_samples() const override { return m_samples.size(); }
    std::vector<nn::ParameterRef> parameters() override { return m_model.network.parameters("integrator."); }
    double loss_and_gradient(const std::vector<Index>& indices, Rng& rng) override
    {
        m_trainer.make_batch(m_samples, indices, rng, m_batch);
        try {
            return m_trainer.loss_and_gradient(m_model, m_batch);
        } catch (const NonFinitePotential& e) {
            const Index column = std::clamp<Index>(e.column, 0, m_batch.size() - 1);
            throw NumericalError("non-finite incremental potential (" + NonFinitePotential::text(e.value) +
                                 ") at training sample " +
                                 std::to_string(m_batch.source[std::size_t(column)]) + " of " +
                                 std::to_string(m_samples.size()) +
                                 " (the decoded state of the network's prediction, or its inertia target, is not finite)");
        }
    }

private:
    IntegratorTrainer& m_trainer;
    LatentMlpModel& m_model;
    const TrainingSamples& m_samples;
    IntegratorBatch m_batch;  ///< refilled every batch (its storage only grows)
};

} // namespace

void fit_input_statistics(LatentMlpModel& model, const TrainingSamples& samples)
{
    const Index S = samples.size();
    MatrixXd inputs(model.input_dim(), S);
    inputs << samples.z_prev, samples.z_prev2, samples.p, samples.p_prev, samples.p_prev2;
    model.inputs = nn::Standardizer::fit(inputs);
    const MatrixXd dz = samples.z_target - samples.z_prev;
    const VectorXd mean = dz.rowwise().mean();
    VectorXd std = ((dz.colwise() - mean).array().square().rowwise().sum() / double(S)).sqrt();
    for (Index c = 0; c < std.size(); ++c) {
        if (!(std[c] > 1e-12)) std[c] = 1.0;
    }
    model.output_scale = std;
}

void IntegratorTrainer::prepare(LatentMlpModel& model, const TrainingSamples& samples)
{
    fit_input_statistics(model, samples);
    if (m_options.loss == IntegratorLoss::SelfSupervised) {
        m_potential.freeze_decoder(m_options.float32_decoder);  // the autoencoder does not change while the integrator trains
        cache_decoded_inputs(samples);
    }
    if (m_options.loss == IntegratorLoss::SelfSupervised && m_options.data_balancing) {
        m_velocity_floor = std::max(m_options.balancing_floor * mean_input_speed(samples), 1e-12);
    }
    model.loss = to_string(m_options.loss);
    model.description = m_options.describe();
    model.overwrite_dirichlet = m_options.overwrite_dirichlet;
    model.boundary = boundary_input();
    if (samples.boundary_input != m_options.boundary_input || samples.p.rows() != model.param_dim)
        throw Error("integrator training: samples with " + std::to_string(samples.p.rows()) + " boundary parameters (" +
                    to_string(samples.boundary_input) + ") for a network taking " + std::to_string(model.param_dim) +
                    " (" + to_string(m_options.boundary_input) +
                    "): make the samples with the trainer's boundary_input()");
}

nn::TrainingLoopOptions IntegratorTrainer::loop_options() const
{
    nn::TrainingLoopOptions loop;
    static_cast<nn::TrainingRunOptions&>(loop) = m_options;
    loop.label = "train " + to_string(m_options.loss);
    loop.trainer = "latent integrator";
    loop.epochs = m_options.epochs;
    loop.batch_size = m_options.batch_size;
    loop.drop_last = false;  // every sample every epoch: ceil(S / batch) near-equal batches
    loop.learning_rate = m_options.learning_rate;
    loop.seed = m_options.seed;
    return loop;
}

std::unique_ptr<nn::Learner> IntegratorTrainer::learner(LatentMlpModel& model, const TrainingSamples& samples)
{
    return std::make_unique<IntegratorLearner>(*this, model, samples);
}

IntegratorTrainSummary IntegratorTrainer::train(LatentMlpModel& model, const TrainingSamples& samples)
{
    Timer timer;
    // The fingerprint: resolved options and the inputs' contents, taken before anything
    // is loaded (the network part identifies the caller's initial weights).
    nn::Fingerprint fingerprint;
    {
        Fnv1a64 net_hash;
        nn::hash_network(net_hash, model.network);
        fingerprint.add("options", resolved_options(samples.size()))
            .add("autoencoder", m_autoencoder.content_hash())
            .add("data", samples_hash(samples))
            .add("physics", physics_content_hash(m_model.spec()))
            .add("network", net_hash.hex());
    }
    prepare(model, samples);
    IntegratorLearner learner(*this, model, samples);
    IntegratorTrainSummary summary = nn::run_training_loop(learner, loop_options(), fingerprint);
    summary.seconds = summary.seconds_before + timer.seconds();  // with the set-up above
    return summary;
}

} // namespace lb
