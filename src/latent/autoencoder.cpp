#include "latent/autoencoder.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/limits.hpp"
#include "core/parse.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "latent/embedding_energy_loss.hpp"
#include "latent/pca.hpp"
#include "nn/adam.hpp"
#include "nn/checkpoint.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "nn/serialization.hpp"
#include "nn/training_loop.hpp"

namespace lb {

namespace {

constexpr const char* kFileFormat = "latentbench.autoencoder/1";
constexpr const char* kCheckpointFormat = "latentbench.autoencoder_checkpoint/2";

std::string join(const std::vector<Index>& v)
{
    std::string s;
    for (std::size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
    return s;
}

void validate_architecture(const AutoencoderOptions& o)
{
    if (o.latent_dim <= 0)
        throw ConfigError("autoencoder: latent_dim must be positive (got " + std::to_string(o.latent_dim) + ")");
    if (o.pca_dim < 0)
        throw ConfigError("autoencoder: pca_dim must be ≥ 0 (got " + std::to_string(o.pca_dim) + "; 0 = no PCA layers)");
    for (Index h : o.hidden)
        if (h <= 0) throw ConfigError("autoencoder: hidden widths must be positive (got '" + join(o.hidden) + "')");
}

void validate_training(const AutoencoderOptions& o)
{
    if (o.epochs < 0) throw ConfigError("autoencoder: epochs must be ≥ 0 (got " + std::to_string(o.epochs) + ")");
    if (o.batch_size < 2)
        throw ConfigError("autoencoder: batch_size must be ≥ 2 for BatchNorm (got " + std::to_string(o.batch_size) + ")");
    if (!(o.learning_rate > 0.0) || !std::isfinite(o.learning_rate))
        throw ConfigError("autoencoder: learning_rate must be positive and finite");
    if (!(o.validation_fraction < 1.0) || !std::isfinite(o.validation_fraction))
        throw ConfigError("autoencoder: validation_fraction must be < 1");
    if (o.patience < 0) throw ConfigError("autoencoder: patience must be ≥ 0 (0: no early stopping)");
    if (o.checkpoint_every < 1) throw ConfigError("autoencoder: checkpoint_every must be ≥ 1");
    if (o.physics_epochs < 0)
        throw ConfigError("autoencoder: physics_epochs must be ≥ 0 (got " + std::to_string(o.physics_epochs) + ")");
    if (!(o.physics_weight >= 0.0) || !std::isfinite(o.physics_weight))
        throw ConfigError("autoencoder: physics_weight must be ≥ 0 and finite");
    if (!(o.physics_learning_rate > 0.0) || !std::isfinite(o.physics_learning_rate))
        throw ConfigError("autoencoder: physics_learning_rate must be positive and finite");
    if (o.physics_batch < 1)
        throw ConfigError("autoencoder: physics_batch must be ≥ 1 (got " + std::to_string(o.physics_batch) + ")");
    if (!(o.physics_penalty_weight > 0.0) || !std::isfinite(o.physics_penalty_weight))
        throw ConfigError("autoencoder: physics_penalty_weight must be positive and finite");
}

nn::Linear& linear_layer(nn::Sequential& net, Index i, const char* what)
{
    auto* lin = dynamic_cast<nn::Linear*>(&net.layer(i));
    if (lin == nullptr) throw std::logic_error(std::string("autoencoder: the ") + what + " is not a Linear layer");
    return *lin;
}

std::string hexfloat(double x) { return nn::exact_text(x); }

long long require_int(const h5::File& f, const std::string& where, const std::string& key, long long min,
                      long long max)
{
    if (!f.has_attribute("/", key)) throw IoError(where + ": missing attribute '" + key + "'");
    const long long v = f.attribute_int("/", key);
    if (v < min || v > max)
        throw IoError(where + ": attribute '" + key + "' is " + std::to_string(v) +
                      ", outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    return v;
}

std::string require_string(const h5::File& f, const std::string& where, const std::string& key)
{
    if (!f.has_attribute("/", key)) throw IoError(where + ": missing attribute '" + key + "'");
    return f.attribute_string("/", key);
}

std::vector<Index> parse_widths(const std::string& text, const std::string& where)
{
    const auto widths = parse_positive_list(text, kMaxWidth);
    if (!widths) throw IoError(where + ": malformed hidden widths '" + text + "' (widths lie in [1, " +
                               std::to_string(kMaxWidth) + "])");
    return *widths;
}

} // namespace

// ---- Autoencoder ----------------------------------------------------------------------

Autoencoder::Autoencoder(const PhysicsSpec& physics, const AutoencoderOptions& options, std::uint64_t seed,
                         NoNetworks)
    : m_options(options), m_encoding(physics, options.frame), m_seed(seed),
      m_length_scale(physics.mesh.bounding_box_diagonal())
{
    validate_architecture(m_options);
    m_options.pca_dim = std::min(m_options.pca_dim, m_encoding.num_features());
}

Autoencoder::Autoencoder(const PhysicsSpec& physics, const AutoencoderOptions& options, std::uint64_t seed)
    : Autoencoder(physics, options, seed, NoNetworks{})
{
    build_networks();
}

void Autoencoder::build_networks()
{
    const bool pca = m_options.pca_dim > 0;
    nn::MlpSpec enc;
    enc.in_dim = m_encoding.num_features();
    enc.hidden.assign(m_options.hidden.rbegin(), m_options.hidden.rend());
    enc.out_dim = m_options.latent_dim;
    enc.activation = nn::ActivationKind::swish;
    enc.batch_norm = m_options.batch_norm;
    enc.residual = m_options.residual;
    enc.pca_dim = m_options.pca_dim;
    enc.pca_placement = pca ? nn::PcaPlacement::input : nn::PcaPlacement::none;

    nn::MlpSpec dec = enc;
    dec.in_dim = m_options.latent_dim;
    dec.hidden = m_options.hidden;
    dec.out_dim = m_encoding.num_features();
    dec.pca_placement = pca ? nn::PcaPlacement::output : nn::PcaPlacement::none;

    Rng rng(m_seed);
    m_encoder = nn::make_mlp(enc, rng);
    m_decoder = nn::make_mlp(dec, rng);
}

double Autoencoder::initialize_pca(const MatrixXd& features)
{
    if (features.rows() != num_features())
        throw std::invalid_argument("Autoencoder::initialize_pca: expected " + std::to_string(num_features()) +
                                    " feature rows, got " + std::to_string(features.rows()));
    if (m_options.pca_dim == 0) return 0.0;
    const Index S = features.cols();
    if (S < 2) throw ConfigError("autoencoder: PCA initialisation needs at least 2 training frames");
    Index d = std::min(m_options.pca_dim, S - 1);
    if (d != m_options.pca_dim) {
        log_info("autoencoder: pca_dim %ld clamped to %ld (%ld training frames)", long(m_options.pca_dim), long(d),
                 long(S));
    }
    PcaBasis pca = compute_pca(features, d);
    // Never wider than the data (issue 39): directions past the numerical rank carry no
    // variance and are an arbitrary completion, which touches the rows the data holds
    // constant (e.g. Dirichlet vertices' boundary-relative offsets) and lets training move them.
    if (pca.rank < d) {
        log_warn("autoencoder: PCA layer clamped from %ld to %ld, the numerical rank of the %ld training frames "
                 "(directions with variance > %.0e of the largest); the rest would carry no data",
                 long(d), long(std::max<Index>(pca.rank, 1)), long(S), kPcaRankTolerance);
        d = std::max<Index>(pca.rank, 1);
        pca.basis.conservativeResize(Eigen::NoChange, d);
        pca.variances.conservativeResize(d);
    }
    if (d != m_options.pca_dim) {
        m_options.pca_dim = d;
        build_networks();
    }
    nn::Linear& first = linear_layer(m_encoder, 0, "encoder's first layer");
    nn::Linear& last = linear_layer(m_decoder, m_decoder.size() - 1, "decoder's last layer");
    assert(first.weight().rows() == d && last.weight().cols() == d);
    first.weight() = pca.basis.transpose();
    first.bias() = -(pca.basis.transpose() * pca.mean);
    last.weight() = pca.basis;
    last.bias() = pca.mean;
    return pca.explained_fraction();
}

MatrixXd Autoencoder::encode(const MatrixXd& X) { return m_encoder.forward(m_encoding.to_features(X), false); }

std::pair<VectorXd, VectorXd> Autoencoder::encode_pair(const VectorXd& first, const VectorXd& second)
{
    MatrixXd X(first.size(), 2);
    X.col(0) = first;
    X.col(1) = second;
    const MatrixXd Z = encode(X);
    return {Z.col(0), Z.col(1)};
}

MatrixXd Autoencoder::decode_features(const MatrixXd& Z)
{
    if (Z.rows() != latent_dim())
        throw std::invalid_argument("Autoencoder::decode_features: expected " + std::to_string(latent_dim()) +
                                    " latent rows, got " + std::to_string(Z.rows()));
    return m_decoder.forward(Z, false);
}

MatrixXd Autoencoder::decode(const MatrixXd& Z, const MatrixXd& bc_targets)
{
    return m_encoding.to_positions(decode_features(Z), bc_targets);
}

MatrixXd Autoencoder::decoder_vjp(const MatrixXd& Z, const MatrixXd& grad_x, const MatrixXd& bc_targets)
{
    return nn::vjp_batch(m_decoder, Z, m_encoding.gradient_to_features(grad_x, bc_targets));
}

double Autoencoder::relative_rmse(const MatrixXd& X, const MatrixXd& bc_targets)
{
    if (X.cols() == 0) return 0.0;
    const MatrixXd X_hat = decode(encode(X), bc_targets);
    const double num_vertices = double(m_encoding.num_dofs() / 3);
    return std::sqrt((X_hat - X).squaredNorm() / (num_vertices * double(X.cols()))) / m_length_scale;
}

std::string Autoencoder::content_hash()
{
    Fnv1a64 h;
    h.add(std::string(m_encoding.kind_name())).add(std::int64_t(m_encoding.num_features()));
    h.add(std::int64_t(m_options.latent_dim));
    const auto& bc = m_encoding.bc_indices();
    h.add(std::int64_t(bc.size())).add_bytes(bc.data(), bc.size() * sizeof(int));
    nn::hash_network(h, m_encoder);
    nn::hash_network(h, m_decoder);
    return h.hex();
}

void Autoencoder::save(const std::string& path, const nn::TrainingCurves& curves)
{
    h5::write_file_atomically(path, [&](h5::File& file) {
        save_into(file, "");
        nn::save_training_curves(file, "", curves);
        const double final_loss = nn::last_train_loss(curves);
        if (!std::isnan(final_loss)) file.set_attribute("/", "final_loss", final_loss);
    });
}

void Autoencoder::save_into(h5::File& file, const std::string& prefix)
{
    nn::save_network(file, prefix + "encoder.", m_encoder);
    nn::save_network(file, prefix + "decoder.", m_decoder);
    file.set_attribute("/", prefix + "format", std::string(kFileFormat));
    file.set_attribute("/", prefix + "latent_dim", (long long)m_options.latent_dim);
    file.set_attribute("/", prefix + "pca_dim", (long long)m_options.pca_dim);
    file.set_attribute("/", prefix + "hidden", join(m_options.hidden));
    file.set_attribute("/", prefix + "batch_norm", (long long)m_options.batch_norm);
    file.set_attribute("/", prefix + "residual", (long long)m_options.residual);
    file.set_attribute("/", prefix + "encoding", std::string(m_encoding.kind_name()));
    file.set_attribute("/", prefix + "num_features", (long long)m_encoding.num_features());
    file.set_attribute("/", prefix + "num_dofs", (long long)m_encoding.num_dofs());
    file.set_attribute("/", prefix + "scene", m_scene_name);
    file.set_attribute("/", prefix + "seed", std::to_string(m_seed));
}

Autoencoder Autoencoder::load(const std::string& path, const PhysicsSpec& physics)
{
    return load_from(h5::File::open(path), "", physics);
}

Autoencoder Autoencoder::load_from(const h5::File& file, const std::string& prefix, const PhysicsSpec& physics)
{
    const std::string where =
        "autoencoder file '" + file.path() + "'" + (prefix.empty() ? std::string() : " (prefix '" + prefix + "')");
    if (!file.has_attribute("/", prefix + "format") || file.attribute_string("/", prefix + "format") != kFileFormat)
        throw IoError(where + ": not a latentbench autoencoder (attribute '" + prefix + "format' is not '" +
                      kFileFormat + "')");

    AutoencoderOptions options;
    options.latent_dim = static_cast<Index>(require_int(file, where, prefix + "latent_dim", 1, kMaxWidth));
    options.pca_dim = static_cast<Index>(require_int(file, where, prefix + "pca_dim", 0, kMaxWidth));
    options.hidden = parse_widths(require_string(file, where, prefix + "hidden"), where);
    options.batch_norm = require_int(file, where, prefix + "batch_norm", 0, 1) != 0;
    options.residual = require_int(file, where, prefix + "residual", 0, 1) != 0;
    const std::string seed_text = file.has_attribute("/", prefix + "seed") ? file.attribute_string("/", prefix + "seed") : "0";
    const std::uint64_t seed = std::strtoull(seed_text.c_str(), nullptr, 10);
    const std::string kind = require_string(file, where, prefix + "encoding");
    const std::string rigid_suffix = "_rigid";
    if (kind.size() > rigid_suffix.size() && kind.compare(kind.size() - rigid_suffix.size(), rigid_suffix.size(), rigid_suffix) == 0)
        options.frame = EncodingFrame::rigid;

    Autoencoder ae = [&] {
        try {
            return Autoencoder(physics, options, seed, NoNetworks{});
        } catch (const ConfigError& e) {
            throw IoError(where + ": " + e.what());
        }
    }();
    const long long F = require_int(file, where, prefix + "num_features", 1, std::numeric_limits<int>::max());
    if (kind != ae.m_encoding.kind_name())
        throw IoError(where + ": made for the '" + kind + "' encoding, but the physics needs '" +
                      ae.m_encoding.kind_name() + "'");
    if (F != ae.num_features())
        throw IoError(where + ": made for " + std::to_string(F) + " features, but the physics has " +
                      std::to_string(ae.num_features()) + " (" + std::to_string(ae.m_encoding.num_dofs()) +
                      " DOF): a different mesh or Dirichlet set");
    ae.m_options.pca_dim = options.pca_dim;  // as saved (already clamped)
    ae.m_encoder = nn::load_network(file, prefix + "encoder.").network;
    ae.m_decoder = nn::load_network(file, prefix + "decoder.").network;
    if (ae.m_encoder.in_features() != F || ae.m_decoder.out_features() != F ||
        ae.m_encoder.out_features() != options.latent_dim || ae.m_decoder.in_features() != options.latent_dim)
        throw IoError(where + ": encoder/decoder shapes do not match latent_dim " +
                      std::to_string(options.latent_dim) + " and " + std::to_string(F) + " features");
    ae.m_scene_name = file.has_attribute("/", prefix + "scene") ? file.attribute_string("/", prefix + "scene") : "";
    return ae;
}

// ---- data ------------------------------------------------------------------------------

std::string to_string(AutoencoderFrames frames) { return frames == AutoencoderFrames::all ? "all" : "train"; }

AutoencoderFrames autoencoder_frames_from_string(const std::string& text)
{
    if (text == "train") return AutoencoderFrames::train;
    if (text == "all") return AutoencoderFrames::all;
    throw ConfigError("unknown value '" + text + "' (train: the training window only; all: every frame)");
}

FrameSet training_frames(const Dataset& data, AutoencoderFrames which)
{
    auto frames_of = [which](const auto& seq) {
        return which == AutoencoderFrames::all ? Index(seq.num_frames())
                                               : std::min<Index>(seq.train_frames, seq.num_frames());
    };
    Index S = 0;
    for (const auto& seq : data.sequences) S += frames_of(seq);
    const Index n = 3 * data.physics.mesh.num_vertices();
    const Index nb = 3 * Index(data.physics.bc_indices.size());
    FrameSet fs;
    fs.positions.resize(n, S);
    fs.bc_targets.resize(nb, S);
    Index j = 0;
    for (const auto& seq : data.sequences) {
        const Index T = frames_of(seq);
        for (Index t = 0; t < T; ++t, ++j) {
            fs.positions.col(j) = seq.positions.row(t).transpose();
            fs.bc_targets.col(j) = seq.bc_positions.row(t).transpose();
        }
    }
    return fs;
}

// ---- training ----------------------------------------------------------------------

namespace {

/// Resolved options (every field that changes the numbers), the training data and the
/// starting networks (architecture, init seed and PCA layers in one hash).
/// @param num_batches, validation_every  as resolved by train_autoencoder
nn::Fingerprint fingerprint(Autoencoder& ae, const AutoencoderOptions& o, const MatrixXd& features,
                            Index num_batches, Index validation_every)
{
    const auto& a = ae.options();
    std::ostringstream os;
    os << "latent=" << a.latent_dim << ";hidden=" << join(a.hidden) << ";pca=" << a.pca_dim
       << ";bn=" << a.batch_norm << ";res=" << a.residual << ";encoding=" << ae.encoding().kind_name()
       << ";init_seed=" << ae.seed() << ";epochs=" << o.epochs << ";batches=" << num_batches
       << ";lr=" << hexfloat(o.learning_rate) << ";validation_every=" << validation_every
       << ";patience=" << o.patience << ";seed=" << o.seed << ";max_seconds=" << hexfloat(o.max_seconds);
    Fnv1a64 data, net;
    data.add(features);
    nn::hash_network(net, ae.encoder());
    nn::hash_network(net, ae.decoder());
    nn::Fingerprint f;
    f.add("options", os.str()).add("data", data.hex()).add("network", net.hex());
    return f;
}

/// Mean squared error per position DOF of the eval-mode reconstruction of `features`.
double eval_mse(Autoencoder& ae, const MatrixXd& features)
{
    if (features.cols() == 0) return 0.0;
    const MatrixXd Y = ae.decoder().forward(ae.encoder().forward(features, false), false);
    return (Y - features).squaredNorm() / (double(ae.encoding().num_dofs()) * double(features.cols()));
}

/// The autoencoder as seen by the shared training loop: reconstruction MSE of the
/// training features, validation MSE in eval mode, best weights and BatchNorm statistics
/// kept by the learner (and saved in checkpoints).
class AutoencoderLearner final : public nn::Learner {
public:
    AutoencoderLearner(Autoencoder& ae, const MatrixXd& train_features, const MatrixXd& val_features)
        : m_ae(ae), m_train(train_features), m_val(val_features), m_best_enc(ae.encoder()),
          m_best_dec(ae.decoder()), m_dofs(double(ae.encoding().num_dofs()))
    {
    }
    Index num_samples() const override { return m_train.cols(); }
    std::vector<nn::ParameterRef> parameters() override
    {
        return autoencoder_parameters(m_ae, "");
    }
    /// ||f̂ − f||² / (3N · n) in training mode (BatchNorm batch statistics).
    double loss_and_gradient(const std::vector<Index>& indices, Rng&) override
    {
        const Index n = Index(indices.size());
        MatrixXd batch(m_train.rows(), n);
        for (Index i = 0; i < n; ++i) batch.col(i) = m_train.col(indices[std::size_t(i)]);
        const MatrixXd Z = m_ae.encoder().forward(batch, true);
        const MatrixXd residual = m_ae.decoder().forward(Z, true) - batch;
        const MatrixXd dZ = m_ae.decoder().backward((2.0 / (m_dofs * double(n))) * residual, true);
        m_ae.encoder().backward(dZ, true);
        return residual.squaredNorm() / (m_dofs * double(n));
    }
    bool has_validation() const override { return true; }
    double validation_loss() override { return eval_mse(m_ae, m_val); }
    void snapshot_best() override
    {
        nn::copy_network_state(m_best_enc, m_ae.encoder());
        nn::copy_network_state(m_best_dec, m_ae.decoder());
    }
    void restore_best() override
    {
        nn::copy_network_state(m_ae.encoder(), m_best_enc);
        nn::copy_network_state(m_ae.decoder(), m_best_dec);
    }
    void save_state(h5::File& file) override
    {
        nn::save_network(file, "encoder.", m_ae.encoder());
        nn::save_network(file, "decoder.", m_ae.decoder());
        nn::save_network(file, "best_encoder.", m_best_enc);
        nn::save_network(file, "best_decoder.", m_best_dec);
    }
    void load_state(const h5::File& file) override
    {
        // Everything into temporaries first (copy_network_state checks names and shapes), then commit.
        auto load_like = [&](nn::Sequential& like, const std::string& prefix) {
            nn::Sequential loaded = nn::load_network(file, prefix).network;
            nn::Sequential out(like);
            nn::copy_network_state(out, loaded);
            return out;
        };
        nn::Sequential enc = load_like(m_ae.encoder(), "encoder.");
        nn::Sequential dec = load_like(m_ae.decoder(), "decoder.");
        nn::Sequential benc = load_like(m_best_enc, "best_encoder.");
        nn::Sequential bdec = load_like(m_best_dec, "best_decoder.");
        nn::copy_network_state(m_ae.encoder(), enc);
        nn::copy_network_state(m_ae.decoder(), dec);
        nn::copy_network_state(m_best_enc, benc);
        nn::copy_network_state(m_best_dec, bdec);
    }

private:
    Autoencoder& m_ae;
    const MatrixXd& m_train;
    const MatrixXd& m_val;
    nn::Sequential m_best_enc, m_best_dec;
    double m_dofs;
};

/// Mean of L_recon and L_ephys over `samples`, in chunks, without gradients.
EmbeddingLossParts mean_embedding_parts(EmbeddingEnergyLoss& loss, const std::vector<FrameSample>& samples,
                                        double ephys_weight)
{
    constexpr Index kChunk = 256;
    EmbeddingLossParts mean;
    const Index S = Index(samples.size());
    for (Index begin = 0; begin < S; begin += kChunk) {
        const Index end = std::min(S, begin + kChunk);
        EmbeddingLossParts p;
        loss.loss({samples.begin() + begin, samples.begin() + end}, 1.0, ephys_weight, false, &p);
        const double f = double(end - begin) / double(S);
        mean.recon += f * p.recon;
        mean.ephys += f * p.ephys;
    }
    return mean;
}

/// The physics fine-tuning of train_autoencoder (options.physics_epochs > 0).
void finetune_physics(Autoencoder& ae, const Dataset& data, const AutoencoderOptions& o,
                      AutoencoderTrainSummary& summary)
{
    Timer timer;
    const PhysicsModel model(data.physics);
    EmbeddingEnergyLoss loss(model, data, ae, o.physics_penalty_weight, "autoencoder physics fine-tuning");
    const std::vector<FrameSample> samples = loss.frame_samples();
    const EmbeddingLossParts before = mean_embedding_parts(loss, samples, o.physics_weight);

    std::ostringstream os;
    os << "physics_epochs=" << o.physics_epochs << ";weight=" << hexfloat(o.physics_weight)
       << ";lr=" << hexfloat(o.physics_learning_rate) << ";batch=" << o.physics_batch
       << ";penalty=" << hexfloat(o.physics_penalty_weight) << ";seed=" << o.seed
       << ";max_seconds=" << hexfloat(o.max_seconds);
    Fnv1a64 frames;
    for (const FrameSequence& s : loss.sequences()) frames.add(s.X).add(s.targets);
    nn::Fingerprint print;
    print.add("options", os.str())
        .add("autoencoder", ae.content_hash())
        .add("data", frames.hex())
        .add("physics", physics_content_hash(data.physics));

    nn::TrainingLoopOptions loop;
    static_cast<nn::TrainingRunOptions&>(loop) = o;
    loop.checkpoint_path = o.checkpoint_path.empty() ? std::string() : o.checkpoint_path + ".physics";
    loop.label = "train-ae physics";
    loop.trainer = "autoencoder physics fine-tuning";
    loop.epochs = o.physics_epochs;
    loop.batch_size = o.physics_batch;
    loop.learning_rate = o.physics_learning_rate;
    loop.seed = o.seed + 1;
    const double weight = o.physics_weight;
    FrameSampleLearner learner(samples, autoencoder_parameters(ae, ""), [&](const std::vector<FrameSample>& b) {
        return loss.loss(b, 1.0, weight, true);
    });
    const nn::TrainingLoopSummary run = nn::run_training_loop(learner, loop, print);
    const EmbeddingLossParts after = mean_embedding_parts(loss, samples, o.physics_weight);
    summary.physics_ran = true;
    summary.physics_recon_before = before.recon;
    summary.physics_recon_after = after.recon;
    summary.physics_ephys_before = before.ephys;
    summary.physics_ephys_after = after.ephys;
    summary.physics_epochs_run = run.epochs_run;
    summary.curves.push_back(run.curve);
    summary.curves.back().stage = "physics";
    summary.physics_seconds = run.seconds_before + timer.seconds();
    summary.seconds_before += run.seconds_before;  // the earlier processes' fine-tuning
    summary.time_limited = summary.time_limited || run.time_limited;
    summary.interrupted = summary.interrupted || run.interrupted;
    if (o.progress)
        log_info("autoencoder physics fine-tuning: %d epochs, L_recon %.4e -> %.4e m², L_ephys %.6g -> %.6g "
                 "(weight %g), %.1f s%s",
                 run.epochs_run, before.recon, after.recon, before.ephys, after.ephys, o.physics_weight,
                 summary.physics_seconds, run.time_limited ? " (time limit)" : "");
}

} // namespace

AutoencoderTrainSummary train_autoencoder(Autoencoder& ae, const Dataset& data, const AutoencoderOptions& options)
{
    validate_training(options);
    Timer timer;
    const BcRelativeEncoding& enc = ae.encoding();
    if (3 * data.physics.mesh.num_vertices() != enc.num_dofs() ||
        data.physics.bc_indices != enc.bc_indices())
        throw ConfigError("train_autoencoder: the dataset's physics (" +
                          std::to_string(3 * data.physics.mesh.num_vertices()) +
                          " DOF) does not match the autoencoder's (" + std::to_string(enc.num_dofs()) + " DOF)");
    if (ae.scene_name().empty()) ae.set_scene_name(data.scene_name);

    // ---- data: features, train / validation split by frame
    const FrameSet frames = training_frames(data, options.frames_seen);
    const MatrixXd all_features = enc.to_features(frames.positions);
    const Index S_all = all_features.cols();
    std::vector<Index> train_idx, val_idx;
    const Index k = options.validation_fraction > 0.0
                        ? std::max<Index>(2, Index(std::llround(1.0 / options.validation_fraction)))
                        : 0;
    for (Index j = 0; j < S_all; ++j) (k > 0 && j % k == k - 1 ? val_idx : train_idx).push_back(j);
    if (train_idx.size() < 2)
        throw ConfigError("train_autoencoder: need at least 2 training frames (have " +
                          std::to_string(train_idx.size()) + " after the validation split)");
    auto gather = [](const MatrixXd& M, const std::vector<Index>& idx) {
        MatrixXd out(M.rows(), Index(idx.size()));
        for (std::size_t i = 0; i < idx.size(); ++i) out.col(Index(i)) = M.col(idx[i]);
        return out;
    };
    const MatrixXd train_features = gather(all_features, train_idx);
    const bool has_validation = !val_idx.empty();
    const MatrixXd val_features = has_validation ? gather(all_features, val_idx) : train_features;
    const MatrixXd val_positions = gather(frames.positions, has_validation ? val_idx : train_idx);
    const MatrixXd val_targets = gather(frames.bc_targets, has_validation ? val_idx : train_idx);
    const Index S = train_features.cols();

    // ---- PCA initialisation (deterministic; a resumed run overwrites it from the checkpoint)
    const double explained = ae.initialize_pca(train_features);
    char pca_text[96];
    if (ae.options().pca_dim > 0)
        std::snprintf(pca_text, sizeof pca_text, "pca %ld (%.6f of the variance)", long(ae.options().pca_dim), explained);
    else
        std::snprintf(pca_text, sizeof pca_text, "no PCA layers");
    log_info("autoencoder: %ld features, latent %ld, %s, %ld train / %ld validation frames%s", long(ae.num_features()),
             long(ae.latent_dim()), pca_text, long(S), long(val_idx.size()),
             has_validation ? "" : " (no validation split: validating on the training frames)");

    // ceil(S / batch_size) batches of near-equal size, but never one of a single frame
    // (training-mode BatchNorm needs two): at most S / 2 batches.
    const Index num_batches = std::min((S + options.batch_size - 1) / options.batch_size, S / 2);
    const nn::Fingerprint print = fingerprint(ae, options, all_features, num_batches, k);
    nn::TrainingLoopOptions loop;
    loop.label = "train-ae";
    loop.trainer = "autoencoder";
    loop.epochs = options.epochs;
    loop.batch_size = options.batch_size;
    loop.min_batch = 2;
    loop.learning_rate = options.learning_rate;
    loop.seed = options.seed;
    loop.patience = options.patience;
    static_cast<nn::TrainingRunOptions&>(loop) = options;
    AutoencoderLearner learner(ae, train_features, val_features);
    AutoencoderTrainSummary summary;
    static_cast<nn::TrainingLoopSummary&>(summary) = nn::run_training_loop(learner, loop, print);
    summary.curves = {summary.curve};
    summary.curves.front().stage = "autoencoder";
    // No epoch run: the PCA-initialised network.
    if (summary.best_epoch == 0) summary.best_validation = eval_mse(ae, val_features);
    summary.validation_relative_rmse_held_out = ae.relative_rmse(val_positions, val_targets);
    summary.validation_relative_rmse = summary.validation_relative_rmse_held_out;
    if (options.physics_epochs > 0 && !summary.interrupted) {
        finetune_physics(ae, data, options, summary);
        summary.validation_relative_rmse = ae.relative_rmse(val_positions, val_targets);
    }
    summary.seconds = summary.seconds_before + timer.seconds();
    if (options.progress)
        log_info("train-ae %s after %d epochs (best %d): validation MSE %.4e, relative RMSE %.4e, %.1fs",
                 summary.stopped_early ? "stopped early" : "finished", summary.epochs_run, summary.best_epoch,
                 summary.best_validation, summary.validation_relative_rmse, summary.seconds);
    return summary;
}

} // namespace lb
