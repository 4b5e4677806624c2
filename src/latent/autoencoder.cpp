#include "latent/autoencoder.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/error.hpp"
#include "core/parse.hpp"
#include "core/log.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "latent/pca.hpp"
#include "nn/adam.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "nn/serialization.hpp"

namespace lb {

namespace {

constexpr const char* kFileFormat = "latentbench.autoencoder/1";
constexpr const char* kCheckpointFormat = "latentbench.autoencoder_checkpoint/1";

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
}

/// Copy parameter values and buffers (BatchNorm statistics) of `src` into `dst`, which
/// must have the same structure; storage of `dst` is kept (an optimiser on it stays valid).
void copy_state(nn::Sequential& dst, nn::Sequential& src)
{
    auto dp = dst.parameters(), sp = src.parameters();
    auto db = dst.buffers(), sb = src.buffers();
    if (dp.size() != sp.size() || db.size() != sb.size())
        throw std::invalid_argument("copy_state: networks differ in structure");
    for (std::size_t i = 0; i < dp.size(); ++i) {
        if (dp[i].name != sp[i].name || dp[i].value.rows() != sp[i].value.rows() ||
            dp[i].value.cols() != sp[i].value.cols())
            throw std::invalid_argument("copy_state: parameter '" + dp[i].name + "' differs");
        dp[i].value = sp[i].value;
    }
    for (std::size_t i = 0; i < db.size(); ++i) {
        if (db[i].name != sb[i].name || db[i].value.size() != sb[i].value.size())
            throw std::invalid_argument("copy_state: buffer '" + db[i].name + "' differs");
        db[i].value = sb[i].value;
    }
}

nn::Linear& linear_layer(nn::Sequential& net, Index i, const char* what)
{
    auto* lin = dynamic_cast<nn::Linear*>(&net.layer(i));
    if (lin == nullptr) throw std::logic_error(std::string("autoencoder: the ") + what + " is not a Linear layer");
    return *lin;
}

// FNV-1a over the bytes of a matrix: identifies the training data in checkpoints.
std::uint64_t fnv1a(const MatrixXd& m, std::uint64_t h = 1469598103934665603ull)
{
    const auto* bytes = reinterpret_cast<const unsigned char*>(m.data());
    const std::size_t n = sizeof(double) * static_cast<std::size_t>(m.size());
    for (std::size_t i = 0; i < n; ++i) {
        h ^= bytes[i];
        h *= 1099511628211ull;
    }
    return h;
}

std::string hexfloat(double x)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%a", x);
    return buf;
}

long long require_int(const h5::File& f, const std::string& key)
{
    if (!f.has_attribute("/", key))
        throw IoError("autoencoder file '" + f.path() + "': missing attribute '" + key + "'");
    return f.attribute_int("/", key);
}

std::string require_string(const h5::File& f, const std::string& key)
{
    if (!f.has_attribute("/", key))
        throw IoError("autoencoder file '" + f.path() + "': missing attribute '" + key + "'");
    return f.attribute_string("/", key);
}

std::vector<Index> parse_widths(const std::string& text, const std::string& where)
{
    const auto widths = parse_positive_list(text);
    if (!widths) throw IoError(where + ": malformed hidden widths '" + text + "'");
    return *widths;
}

} // namespace

// ---- Autoencoder ----------------------------------------------------------------------

Autoencoder::Autoencoder(const PhysicsSpec& physics, const AutoencoderOptions& options, std::uint64_t seed,
                         NoNetworks)
    : m_options(options), m_encoding(physics), m_seed(seed),
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
    const Index d = std::min(m_options.pca_dim, S - 1);
    if (d != m_options.pca_dim) {
        log_info("autoencoder: pca_dim %ld clamped to %ld (%ld training frames)", long(m_options.pca_dim), long(d),
                 long(S));
        m_options.pca_dim = d;
        build_networks();
    }
    const PcaBasis pca = compute_pca(features, d);
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

MatrixXd Autoencoder::decoder_vjp(const MatrixXd& Z, const MatrixXd& grad_x)
{
    return nn::vjp_batch(m_decoder, Z, m_encoding.gradient_to_features(grad_x));
}

double Autoencoder::relative_rmse(const MatrixXd& X, const MatrixXd& bc_targets)
{
    if (X.cols() == 0) return 0.0;
    const MatrixXd X_hat = decode(encode(X), bc_targets);
    const double num_vertices = double(m_encoding.num_dofs() / 3);
    return std::sqrt((X_hat - X).squaredNorm() / (num_vertices * double(X.cols()))) / m_length_scale;
}

void Autoencoder::save(const std::string& path)
{
    h5::AtomicOutput output(path);
    {
        h5::File file = h5::File::create(output.temp_path());
        nn::save_network(file, "encoder.", m_encoder);
        nn::save_network(file, "decoder.", m_decoder);
        file.set_attribute("/", "format", std::string(kFileFormat));
        file.set_attribute("/", "latent_dim", (long long)m_options.latent_dim);
        file.set_attribute("/", "pca_dim", (long long)m_options.pca_dim);
        file.set_attribute("/", "hidden", join(m_options.hidden));
        file.set_attribute("/", "batch_norm", (long long)m_options.batch_norm);
        file.set_attribute("/", "residual", (long long)m_options.residual);
        file.set_attribute("/", "encoding", std::string(m_encoding.kind_name()));
        file.set_attribute("/", "num_features", (long long)m_encoding.num_features());
        file.set_attribute("/", "num_dofs", (long long)m_encoding.num_dofs());
        file.set_attribute("/", "scene", m_scene_name);
        file.set_attribute("/", "seed", std::to_string(m_seed));
    }
    output.commit();
}

Autoencoder Autoencoder::load(const std::string& path, const PhysicsSpec& physics)
{
    const h5::File file = h5::File::open(path);
    const std::string where = "autoencoder file '" + path + "'";
    if (!file.has_attribute("/", "format") || file.attribute_string("/", "format") != kFileFormat)
        throw IoError(where + ": not a latentbench autoencoder (attribute 'format' is not '" + kFileFormat + "')");

    AutoencoderOptions options;
    options.latent_dim = static_cast<Index>(require_int(file, "latent_dim"));
    options.pca_dim = static_cast<Index>(require_int(file, "pca_dim"));
    options.hidden = parse_widths(require_string(file, "hidden"), where);
    options.batch_norm = require_int(file, "batch_norm") != 0;
    options.residual = require_int(file, "residual") != 0;
    const std::string seed_text = file.has_attribute("/", "seed") ? file.attribute_string("/", "seed") : "0";
    const std::uint64_t seed = std::strtoull(seed_text.c_str(), nullptr, 10);

    Autoencoder ae = [&] {
        try {
            return Autoencoder(physics, options, seed, NoNetworks{});
        } catch (const ConfigError& e) {
            throw IoError(where + ": " + e.what());
        }
    }();
    const long long F = require_int(file, "num_features");
    const std::string kind = require_string(file, "encoding");
    if (kind != ae.m_encoding.kind_name())
        throw IoError(where + ": made for the '" + kind + "' encoding, but the physics needs '" +
                      ae.m_encoding.kind_name() + "'");
    if (F != ae.num_features())
        throw IoError(where + ": made for " + std::to_string(F) + " features, but the physics has " +
                      std::to_string(ae.num_features()) + " (" + std::to_string(ae.m_encoding.num_dofs()) +
                      " DOF): a different mesh or Dirichlet set");
    ae.m_options.pca_dim = options.pca_dim;  // as saved (already clamped)
    ae.m_encoder = nn::load_network(file, "encoder.").network;
    ae.m_decoder = nn::load_network(file, "decoder.").network;
    if (ae.m_encoder.in_features() != F || ae.m_decoder.out_features() != F ||
        ae.m_encoder.out_features() != options.latent_dim || ae.m_decoder.in_features() != options.latent_dim)
        throw IoError(where + ": encoder/decoder shapes do not match latent_dim " +
                      std::to_string(options.latent_dim) + " and " + std::to_string(F) + " features");
    ae.m_scene_name = file.has_attribute("/", "scene") ? file.attribute_string("/", "scene") : "";
    return ae;
}

// ---- data ------------------------------------------------------------------------------

FrameSet training_frames(const Dataset& data)
{
    Index S = 0;
    for (const auto& seq : data.sequences) S += std::min<Index>(seq.train_frames, seq.num_frames());
    const Index n = 3 * data.physics.mesh.num_vertices();
    const Index nb = 3 * Index(data.physics.bc_indices.size());
    FrameSet fs;
    fs.positions.resize(n, S);
    fs.bc_targets.resize(nb, S);
    Index j = 0;
    for (const auto& seq : data.sequences) {
        const Index T = std::min<Index>(seq.train_frames, seq.num_frames());
        for (Index t = 0; t < T; ++t, ++j) {
            fs.positions.col(j) = seq.positions.row(t).transpose();
            fs.bc_targets.col(j) = seq.bc_positions.row(t).transpose();
        }
    }
    return fs;
}

// ---- training ----------------------------------------------------------------------

namespace {

struct TrainingState {
    int epoch = 0;                   ///< epochs completed
    int best_epoch = 0;
    double best_validation_mse = std::numeric_limits<double>::infinity();
    int epochs_since_improvement = 0;
    double last_train_mse = 0.0;
};

std::string fingerprint(const Autoencoder& ae, const AutoencoderOptions& o, const MatrixXd& features)
{
    const auto& a = ae.options();
    std::ostringstream os;
    os << "latent=" << a.latent_dim << ";hidden=" << join(a.hidden) << ";pca=" << a.pca_dim
       << ";bn=" << a.batch_norm << ";res=" << a.residual << ";encoding=" << ae.encoding().kind_name()
       << ";init_seed=" << ae.seed() << ";seed=" << o.seed << ";batch=" << o.batch_size
       << ";lr=" << hexfloat(o.learning_rate) << ";val=" << hexfloat(o.validation_fraction)
       << ";features=" << features.rows() << "x" << features.cols() << ";data=" << std::hex << fnv1a(features);
    return os.str();
}

void write_checkpoint(const std::string& path, const std::string& print, Autoencoder& ae, nn::Sequential& best_enc,
                      nn::Sequential& best_dec, const nn::Adam& adam,
                      const std::vector<nn::ParameterRef>& params, Rng& rng, const TrainingState& st)
{
    h5::AtomicOutput output(path);
    {
        h5::File file = h5::File::create(output.temp_path());
        nn::save_network(file, "encoder.", ae.encoder());
        nn::save_network(file, "decoder.", ae.decoder());
        nn::save_network(file, "best_encoder.", best_enc);
        nn::save_network(file, "best_decoder.", best_dec);
        const nn::AdamState& s = adam.state();
        for (std::size_t i = 0; i < params.size(); ++i) {
            file.write("adam/m/" + params[i].name, s.m[i]);
            file.write("adam/v/" + params[i].name, s.v[i]);
        }
        std::ostringstream rng_state;
        rng_state << rng.engine();
        file.set_attribute("/", "format", std::string(kCheckpointFormat));
        file.set_attribute("/", "fingerprint", print);
        file.set_attribute("/", "rng_state", rng_state.str());
        file.set_attribute("/", "adam_step", (long long)s.step);
        file.set_attribute("/", "epoch", (long long)st.epoch);
        file.set_attribute("/", "best_epoch", (long long)st.best_epoch);
        file.set_attribute("/", "best_validation_mse", hexfloat(st.best_validation_mse));
        file.set_attribute("/", "epochs_since_improvement", (long long)st.epochs_since_improvement);
        file.set_attribute("/", "last_train_mse", hexfloat(st.last_train_mse));
    }
    output.commit();
}

/// Returns false (with a warning) if the checkpoint was made differently; throws
/// IoError if it claims to match but cannot be read.
bool read_checkpoint(const std::string& path, const std::string& print, Autoencoder& ae, nn::Sequential& best_enc,
                     nn::Sequential& best_dec, nn::Adam& adam, const std::vector<nn::ParameterRef>& params,
                     Rng& rng, TrainingState& st)
{
    const h5::File file = h5::File::open(path);
    const std::string where = "checkpoint '" + path + "'";
    if (!file.has_attribute("/", "format") || file.attribute_string("/", "format") != kCheckpointFormat) {
        log_warn("%s is not an autoencoder checkpoint; starting from scratch (it will be overwritten)", path.c_str());
        return false;
    }
    if (file.attribute_string("/", "fingerprint") != print) {
        log_warn("%s was made with different options or data; starting from scratch (it will be overwritten)",
                 path.c_str());
        log_debug("checkpoint fingerprint %s, this run %s", file.attribute_string("/", "fingerprint").c_str(),
                  print.c_str());
        return false;
    }
    try {
        auto load_into = [&](nn::Sequential& dst, const std::string& prefix) {
            nn::Sequential loaded = nn::load_network(file, prefix).network;
            copy_state(dst, loaded);
        };
        load_into(ae.encoder(), "encoder.");
        load_into(ae.decoder(), "decoder.");
        load_into(best_enc, "best_encoder.");
        load_into(best_dec, "best_decoder.");
        nn::AdamState s;
        s.step = file.attribute_int("/", "adam_step");
        for (const auto& p : params) {
            s.m.push_back(file.read_matrix("adam/m/" + p.name));
            s.v.push_back(file.read_matrix("adam/v/" + p.name));
        }
        adam.set_state(std::move(s));
        std::istringstream rng_state(file.attribute_string("/", "rng_state"));
        rng_state >> rng.engine();
        if (rng_state.fail()) throw IoError(where + ": malformed 'rng_state'");
        st.epoch = int(file.attribute_int("/", "epoch"));
        st.best_epoch = int(file.attribute_int("/", "best_epoch"));
        st.best_validation_mse = std::strtod(file.attribute_string("/", "best_validation_mse").c_str(), nullptr);
        st.epochs_since_improvement = int(file.attribute_int("/", "epochs_since_improvement"));
        st.last_train_mse = std::strtod(file.attribute_string("/", "last_train_mse").c_str(), nullptr);
    } catch (const std::invalid_argument& e) {
        throw IoError(where + ": " + e.what() + " (delete it to start from scratch)");
    } catch (const IoError& e) {
        throw IoError(std::string(e.what()) + " (delete " + path + " to start from scratch)");
    }
    return true;
}

/// Mean squared error per position DOF of the eval-mode reconstruction of `features`.
double eval_mse(Autoencoder& ae, const MatrixXd& features)
{
    if (features.cols() == 0) return 0.0;
    const MatrixXd Y = ae.decoder().forward(ae.encoder().forward(features, false), false);
    return (Y - features).squaredNorm() / (double(ae.encoding().num_dofs()) * double(features.cols()));
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
    const FrameSet frames = training_frames(data);
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

    std::vector<nn::ParameterRef> params = ae.encoder().parameters("encoder.");
    for (auto& p : ae.decoder().parameters("decoder.")) params.push_back(p);
    nn::AdamOptions adam_options;
    adam_options.lr = options.learning_rate;
    nn::Adam adam(params, adam_options);
    Rng rng(options.seed);
    nn::Sequential best_enc(ae.encoder()), best_dec(ae.decoder());
    TrainingState st;

    AutoencoderTrainSummary summary;
    const std::string print = fingerprint(ae, options, all_features);
    const bool checkpointing = !options.checkpoint_path.empty();
    if (checkpointing && std::filesystem::exists(options.checkpoint_path)) {
        summary.resumed =
            read_checkpoint(options.checkpoint_path, print, ae, best_enc, best_dec, adam, params, rng, st);
        if (summary.resumed)
            log_info("autoencoder: resuming from checkpoint %s at epoch %d (best validation MSE %.4e at epoch %d)",
                     options.checkpoint_path.c_str(), st.epoch, st.best_validation_mse, st.best_epoch);
    }

    // ---- epochs
    const double dof_count = double(enc.num_dofs());
    // ceil(S / batch_size) batches of near-equal size, but never one of a single frame
    // (training-mode BatchNorm needs two): at most S / 2 batches.
    const Index num_batches = std::min((S + options.batch_size - 1) / options.batch_size, S / 2);
    std::vector<Index> order(static_cast<std::size_t>(S));
    const int start_epoch = st.epoch;
    double last_report = -1e300;
    auto early_stop = [&] { return options.patience > 0 && st.epochs_since_improvement >= options.patience; };
    auto checkpoint = [&] {
        if (checkpointing)
            write_checkpoint(options.checkpoint_path, print, ae, best_enc, best_dec, adam, params, rng, st);
    };
    while (st.epoch < options.epochs && !early_stop()) {
        for (Index i = 0; i < S; ++i) order[std::size_t(i)] = i;
        for (Index i = S - 1; i > 0; --i) std::swap(order[std::size_t(i)], order[std::size_t(rng.index(i + 1))]);

        double sq_sum = 0.0;
        Index begin = 0;
        for (Index b = 0; b < num_batches; ++b) {
            const Index end = S * (b + 1) / num_batches;  // near-equal batch sizes
            const Index n = end - begin;
            MatrixXd batch(train_features.rows(), n);
            for (Index i = 0; i < n; ++i) batch.col(i) = train_features.col(order[std::size_t(begin + i)]);
            adam.zero_grad();
            const MatrixXd Z = ae.encoder().forward(batch, true);
            const MatrixXd residual = ae.decoder().forward(Z, true) - batch;
            sq_sum += residual.squaredNorm();
            const MatrixXd dZ = ae.decoder().backward((2.0 / (dof_count * double(n))) * residual, true);
            ae.encoder().backward(dZ, true);
            adam.step();
            begin = end;
        }
        ++st.epoch;
        st.last_train_mse = sq_sum / (dof_count * double(S));
        const double val_mse = eval_mse(ae, val_features);
        if (!std::isfinite(st.last_train_mse) || !std::isfinite(val_mse))
            throw NumericalError("train_autoencoder: the loss became non-finite at epoch " + std::to_string(st.epoch) +
                                 " (try a smaller learning rate)");
        if (val_mse < st.best_validation_mse) {
            st.best_validation_mse = val_mse;
            st.best_epoch = st.epoch;
            st.epochs_since_improvement = 0;
            copy_state(best_enc, ae.encoder());
            copy_state(best_dec, ae.decoder());
        } else {
            ++st.epochs_since_improvement;
        }
        if (st.epoch % options.checkpoint_every == 0) checkpoint();

        const double elapsed = timer.seconds();
        if (options.progress && (elapsed - last_report >= 2.0 || st.epoch == options.epochs)) {
            last_report = elapsed;
            const double eta = elapsed / double(st.epoch - start_epoch) * double(options.epochs - st.epoch);
            log_info("train-ae epoch %d/%d  train MSE %.4e  validation MSE %.4e  (best %.4e @ %d)  elapsed %.1fs  "
                     "eta %.1fs",
                     st.epoch, options.epochs, st.last_train_mse, val_mse, st.best_validation_mse, st.best_epoch,
                     elapsed, eta);
        }
    }
    summary.stopped_early = early_stop() && st.epoch < options.epochs;
    if (checkpointing && st.epoch % options.checkpoint_every != 0) checkpoint();

    // ---- keep the best-validation weights
    if (st.best_epoch > 0) {
        copy_state(ae.encoder(), best_enc);
        copy_state(ae.decoder(), best_dec);
    } else {
        st.best_validation_mse = eval_mse(ae, val_features);  // no epoch run: the PCA-initialised network
    }
    summary.epochs_run = st.epoch;
    summary.best_epoch = st.best_epoch;
    summary.best_validation_mse = st.best_validation_mse;
    summary.final_train_mse = st.last_train_mse;
    summary.validation_relative_rmse = ae.relative_rmse(val_positions, val_targets);
    summary.seconds = timer.seconds();
    if (options.progress)
        log_info("train-ae %s after %d epochs (best %d): validation MSE %.4e, relative RMSE %.4e, %.1fs",
                 summary.stopped_early ? "stopped early" : "finished", summary.epochs_run, summary.best_epoch,
                 summary.best_validation_mse, summary.validation_relative_rmse, summary.seconds);
    return summary;
}

} // namespace lb
