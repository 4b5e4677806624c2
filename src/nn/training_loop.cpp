#include "nn/training_loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <numeric>

#include "core/error.hpp"
#include "core/limits.hpp"
#include "core/log.hpp"
#include "core/stop_signal.hpp"
#include "core/timer.hpp"
#include "nn/adam.hpp"

namespace lb::nn {

namespace {

constexpr const char* kFormat = "latentbench.training_checkpoint/1";

struct Counters {
    int epoch = 0;  ///< epochs completed
    int best_epoch = 0;
    double best_validation = std::numeric_limits<double>::infinity();
    int epochs_since_improvement = 0;
    double last_loss = 0.0;
    /// Wall-clock seconds of training up to the checkpoint, earlier processes included (0 from
    /// a checkpoint written before it was recorded).
    double seconds = 0.0;
    /// The loss of every epoch so far (validation: one per epoch if the learner has it).
    std::vector<double> train_curve, validation_curve;
};

constexpr const char* kTrainerKey = "trainer";
/// The loss curve's datasets in a checkpoint (nn/training_curve.hpp, save_curve_data).
constexpr const char* kCurveGroup = "curve";

std::string trainer_of(const TrainingLoopOptions& o) { return o.trainer.empty() ? o.label : o.trainer; }

void write_checkpoint(const std::string& path, const std::string& trainer, const Fingerprint& fingerprint,
                      Learner& learner, const std::vector<ParameterRef>& params, const Adam& adam, const Counters& c)
{
    h5::write_file_atomically(path, [&](h5::File& f) {
        f.set_attribute("/", "format", std::string(kFormat));
        f.set_attribute("/", kTrainerKey, trainer);
        write_fingerprint(f, fingerprint);
        const AdamState& s = adam.state();
        for (std::size_t i = 0; i < params.size(); ++i) {
            f.write("param/" + params[i].name, MatrixXd(params[i].value));
            f.write("adam/m/" + params[i].name, s.m[i]);
            f.write("adam/v/" + params[i].name, s.v[i]);
        }
        f.set_attribute("/", "adam_step", (long long)s.step);
        f.set_attribute("/", "epoch", (long long)c.epoch);
        f.set_attribute("/", "best_epoch", (long long)c.best_epoch);
        f.set_attribute("/", "best_validation", exact_text(c.best_validation));
        f.set_attribute("/", "epochs_since_improvement", (long long)c.epochs_since_improvement);
        f.set_attribute("/", "last_loss", exact_text(c.last_loss));
        f.set_attribute("/", "train_seconds", exact_text(c.seconds));
        TrainingCurve curve;
        curve.train_loss = c.train_curve;
        curve.validation_loss = c.validation_curve;
        save_curve_data(f, kCurveGroup, curve);
        learner.save_state(f);
    });
}

/// "a,b,c" → {a, b, c}.
std::vector<std::string> comma_list(const std::string& text)
{
    std::vector<std::string> out;
    std::size_t begin = 0;
    for (std::size_t end; (end = text.find(',', begin)) != std::string::npos; begin = end + 1)
        out.push_back(text.substr(begin, end - begin));
    out.push_back(text.substr(begin));
    return out;
}

/// Why the training checkpoint `f` is another trainer's, or "". Its "trainer" attribute
/// says; one written before that was recorded is another's if exactly one of the two
/// fingerprints has an "autoencoder" part (the autoencoder's trainer against a trainer
/// in its latent space, the mistake of giving `fit` the checkpoint of `train-ae`).
std::string other_trainer(const h5::File& f, const std::string& trainer, const Fingerprint& fingerprint)
{
    if (f.has_attribute("/", kTrainerKey)) {
        const std::string theirs = f.attribute_string("/", kTrainerKey);
        return theirs == trainer ? "" : "is a checkpoint of the '" + theirs + "' trainer, not of '" + trainer + "'";
    }
    if (!f.has_attribute("/", "fingerprint.parts")) return "";
    const std::vector<std::string> parts = comma_list(f.attribute_string("/", "fingerprint.parts"));
    const bool theirs = std::find(parts.begin(), parts.end(), "autoencoder") != parts.end();
    bool ours = false;
    for (const auto& part : fingerprint.parts) ours = ours || part.first == "autoencoder";
    if (theirs == ours) return "";
    return std::string("is a checkpoint of another trainer (one ") + (theirs ? "in an autoencoder's latent space" :
                                                                                "of an autoencoder itself") +
           "), not of '" + trainer + "'";
}

/// ConfigError unless `path` may be replaced by a checkpoint of this trainer: it is one
/// (of any version, or damaged: those are set aside), or an empty file. A file of another
/// kind (a dataset, an autoencoder, a text file, another trainer's checkpoint) given as
/// --checkpoint by mistake is refused, never set aside or overwritten.
void refuse_foreign_checkpoint(const std::string& path, const TrainingLoopOptions& o, const Fingerprint& fingerprint)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    const auto refuse = [&](const std::string& what) {
        throw ConfigError(o.label + ": checkpoint '" + path + "' " + what +
                          "; refusing to set it aside or replace it: it is left as it is (choose another "
                          "checkpoint path)");
    };
    const auto foreign = [&](const std::string& what) { refuse(what + ", not a training checkpoint"); };
    if (fs::is_directory(path, ec)) foreign("is a directory");
    if (fs::file_size(path, ec) == 0 && !ec) return;  // nothing to lose
    if (H5Fis_hdf5(path.c_str()) <= 0) foreign("is not an HDF5 file");
    std::string format, other;
    try {
        const h5::File f = h5::File::open(path);
        if (!f.has_attribute("/", "format")) foreign("is an HDF5 file without a 'format' attribute (a dataset?)");
        format = f.attribute_string("/", "format");
        if (format.rfind("latentbench.training_checkpoint/", 0) == 0) other = other_trainer(f, trainer_of(o), fingerprint);
    } catch (const ConfigError&) {
        throw;
    } catch (const Error&) {
        return;  // an HDF5 file that cannot be read: a damaged checkpoint, set aside by the caller
    }
    if (format.rfind("latentbench.training_checkpoint/", 0) != 0) foreign("is a '" + format + "' file");
    if (!other.empty()) refuse(other);
}

/// The checkpoint's loss curve into `t` (whose counters are read): the reason it is
/// inconsistent with them, or empty. A checkpoint written before curves were recorded has
/// none: its epochs get NaN ("not recorded"), except what the counters know (the last
/// epoch's loss, the best validation loss at its epoch).
std::string read_curve(const h5::File& f, bool validation, Counters& t)
{
    const std::size_t epochs = std::size_t(t.epoch);
    if (!f.exists(std::string(kCurveGroup) + "/train_loss")) {
        constexpr double unknown = std::numeric_limits<double>::quiet_NaN();
        t.train_curve.assign(epochs, unknown);
        if (epochs > 0) t.train_curve.back() = t.last_loss;
        if (validation) {
            t.validation_curve.assign(epochs, unknown);
            if (t.best_epoch > 0) t.validation_curve[std::size_t(t.best_epoch - 1)] = t.best_validation;
        }
        return {};
    }
    TrainingCurve curve = load_curve_data(f, kCurveGroup);
    if (curve.train_loss.size() != epochs)
        return "its loss curve has " + std::to_string(curve.train_loss.size()) + " epochs, its counters " +
               std::to_string(epochs);
    if (epochs > 0 && !(curve.train_loss.back() == t.last_loss))
        return "its loss curve does not end at its last loss";
    if (validation && curve.validation_loss.size() != epochs)
        return "its validation curve has " + std::to_string(curve.validation_loss.size()) + " epochs, its counters " +
               std::to_string(epochs);
    t.train_curve = std::move(curve.train_loss);
    t.validation_curve = validation ? std::move(curve.validation_loss) : std::vector<double>{};
    return {};
}

/// Resume, all or nothing: the reason it cannot be resumed (nothing changed), or empty.
std::string read_checkpoint(const std::string& path, const Fingerprint& fingerprint, Learner& learner,
                            std::vector<ParameterRef>& params, Adam& adam, Counters& c)
{
    try {
        const h5::File f = h5::File::open(path);
        if (!f.has_attribute("/", "format") || f.attribute_string("/", "format") != kFormat)
            return "it is not a training checkpoint of this version";
        if (std::string reason = fingerprint_mismatch(f, fingerprint); !reason.empty()) return reason;
        std::vector<MatrixXd> values;
        AdamState s;
        for (const ParameterRef& p : params) {
            for (const char* group : {"param/", "adam/m/", "adam/v/"}) {
                if (!f.exists(group + p.name))
                    throw CheckpointMismatch("'" + std::string(group) + p.name + "' is missing");
            }
            values.push_back(f.read_matrix("param/" + p.name));
            s.m.push_back(f.read_matrix("adam/m/" + p.name));
            s.v.push_back(f.read_matrix("adam/v/" + p.name));
            for (const MatrixXd* m : {&values.back(), &s.m.back(), &s.v.back()}) {
                if (!m->allFinite())
                    return "it holds non-finite values (NaN or inf) in the parameters or Adam state of '" + p.name + "'";
            }
            require_shape(p.name, values.back(), p.value.rows(), p.value.cols());
            require_shape("adam/m/" + p.name, s.m.back(), p.value.rows(), p.value.cols());
            require_shape("adam/v/" + p.name, s.v.back(), p.value.rows(), p.value.cols());
        }
        const long long step = f.attribute_int("/", "adam_step");
        const long long epoch = f.attribute_int("/", "epoch");
        const long long best_epoch = f.attribute_int("/", "best_epoch");
        const long long since = f.attribute_int("/", "epochs_since_improvement");
        if (epoch < 0 || epoch > kMaxEpochs || best_epoch < 0 || best_epoch > epoch || since < 0 || since > epoch ||
            step < 0)
            return "its counters are inconsistent (epoch " + std::to_string(epoch) + ", best epoch " +
                   std::to_string(best_epoch) + ", Adam step " + std::to_string(step) + ")";
        s.step = step;
        Counters t;
        t.epoch = int(epoch);
        t.best_epoch = int(best_epoch);
        t.best_validation = std::strtod(f.attribute_string("/", "best_validation").c_str(), nullptr);
        t.epochs_since_improvement = int(since);
        t.last_loss = std::strtod(f.attribute_string("/", "last_loss").c_str(), nullptr);
        if (f.has_attribute("/", "train_seconds")) {
            t.seconds = std::strtod(f.attribute_string("/", "train_seconds").c_str(), nullptr);
            if (!(t.seconds >= 0.0) || !std::isfinite(t.seconds)) return "its training time is not a finite number ≥ 0";
        }
        if (std::isnan(t.best_validation) || !std::isfinite(t.last_loss))
            return "its loss record is not finite";
        if (std::string reason = read_curve(f, learner.has_validation(), t); !reason.empty()) return reason;
        learner.load_state(f);  // all or nothing; below nothing can fail (shapes checked)
        adam.set_state(std::move(s));
        for (std::size_t i = 0; i < params.size(); ++i) params[i].value = values[i];
        c = t;
    } catch (const CheckpointMismatch& e) {
        return std::string("its shapes differ: ") + e.what();
    } catch (const std::invalid_argument& e) {
        return std::string("its shapes differ: ") + e.what();
    } catch (const Error& e) {
        return std::string("it cannot be read: ") + e.what();
    }
    return {};
}

} // namespace

std::uint64_t epoch_seed(std::uint64_t seed, int epoch)
{
    std::uint64_t z = seed + 0x9e3779b97f4a7c15ull * (std::uint64_t(epoch) + 1);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

namespace {

/// ConfigError naming the option; returns the smallest batch.
Index check_options(const TrainingLoopOptions& o, Index num_samples)
{
    const Index min_batch = std::max<Index>(o.min_batch, 1);
    if (o.epochs < 0) throw ConfigError(o.label + ": epochs must be ≥ 0");
    if (o.batch_size < min_batch) throw ConfigError(o.label + ": batch_size must be ≥ " + std::to_string(min_batch));
    if (!(o.learning_rate > 0.0) || !std::isfinite(o.learning_rate))
        throw ConfigError(o.label + ": learning_rate must be positive and finite");
    if (o.checkpoint_every < 1) throw ConfigError(o.label + ": checkpoint_every must be ≥ 1");
    if (num_samples < min_batch) throw ConfigError(o.label + ": need at least " + std::to_string(min_batch) + " samples");
    return min_batch;
}

/// Batch boundaries into an epoch's shuffled order: [bounds[b], bounds[b+1]).
std::vector<Index> batch_bounds(const TrainingLoopOptions& o, Index S, Index min_batch)
{
    std::vector<Index> bounds{0};
    if (o.drop_last) {
        const Index full = S / o.batch_size;
        if (full == 0) return {0, S};
        for (Index b = 1; b <= full; ++b) bounds.push_back(b * o.batch_size);
        return bounds;
    }
    // ceil(S / batch_size) batches of near-equal size, none smaller than min_batch.
    const Index num_batches = std::max<Index>(1, std::min((S + o.batch_size - 1) / o.batch_size, S / min_batch));
    for (Index b = 0; b < num_batches; ++b) bounds.push_back(S * (b + 1) / num_batches);
    return bounds;
}

/// Track the best validation loss (snapshotting the learner's weights there).
void track_validation(Learner& learner, double val, Counters& c)
{
    if (val < c.best_validation) {
        c.best_validation = val;
        c.best_epoch = c.epoch;
        c.epochs_since_improvement = 0;
        learner.snapshot_best();
    } else {
        ++c.epochs_since_improvement;
    }
}

void report_epoch(Progress& progress, const Counters& c, bool validation, double val)
{
    char extra[160];
    if (validation)
        std::snprintf(extra, sizeof extra, "loss %.4e  validation %.4e (best %.4e @ %d)", c.last_loss, val,
                      c.best_validation, c.best_epoch);
    else
        std::snprintf(extra, sizeof extra, "loss %.6g", c.last_loss);
    progress.update(c.epoch, extra);
}

} // namespace

EpochRunner::EpochRunner(Learner& learner, const TrainingLoopOptions& o)
    : m_learner(learner),
      m_seed(o.seed),
      m_params(learner.parameters()),
      m_adam(m_params, [&] {
          AdamOptions a;
          a.lr = o.learning_rate;
          return a;
      }()),
      m_bounds(batch_bounds(o, learner.num_samples(), check_options(o, learner.num_samples()))),
      m_order(static_cast<std::size_t>(learner.num_samples()))
{
    Index largest = 0;
    for (std::size_t b = 0; b + 1 < m_bounds.size(); ++b) largest = std::max(largest, m_bounds[b + 1] - m_bounds[b]);
    m_batch.reserve(static_cast<std::size_t>(largest));
}

double EpochRunner::run(int epoch)
{
    const Index S = Index(m_order.size());
    Rng rng(epoch_seed(m_seed, epoch));
    std::iota(m_order.begin(), m_order.end(), Index(0));
    for (Index i = S - 1; i > 0; --i) std::swap(m_order[std::size_t(i)], m_order[std::size_t(rng.index(i + 1))]);
    double weighted = 0.0;
    for (std::size_t b = 0; b + 1 < m_bounds.size(); ++b) {
        m_batch.assign(m_order.begin() + m_bounds[b], m_order.begin() + m_bounds[b + 1]);
        m_adam.zero_grad();
        weighted += m_learner.loss_and_gradient(m_batch, rng) * double(m_batch.size());
        m_adam.step();
    }
    return weighted / double(m_bounds.back());
}

std::optional<CheckpointProgress> read_checkpoint_progress(const std::string& path)
{
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec) || H5Fis_hdf5(path.c_str()) <= 0) return std::nullopt;
    try {
        const h5::File f = h5::File::open(path);
        if (!f.has_attribute("/", "format") ||
            f.attribute_string("/", "format").rfind("latentbench.training_checkpoint/", 0) != 0 ||
            !f.has_attribute("/", "epoch"))
            return std::nullopt;
        CheckpointProgress p;
        p.epoch = int(f.attribute_int("/", "epoch"));
        if (f.has_attribute("/", kTrainerKey)) p.trainer = f.attribute_string("/", kTrainerKey);
        if (f.has_attribute("/", "train_seconds"))
            p.seconds = std::strtod(f.attribute_string("/", "train_seconds").c_str(), nullptr);
        if (f.has_attribute("/", "fingerprint.options")) {
            const std::string options = ";" + f.attribute_string("/", "fingerprint.options");
            const std::size_t at = options.find(";epochs=");
            if (at != std::string::npos) p.epochs = std::atoi(options.c_str() + at + 8);
        }
        return p;
    } catch (const Error&) {
        return std::nullopt;
    }
}

TrainingLoopSummary run_training_loop(Learner& learner, const TrainingLoopOptions& o, const Fingerprint& fingerprint)
{
    EpochRunner runner(learner, o);
    Timer timer;
    TrainingLoopSummary summary;
    std::vector<ParameterRef>& params = runner.parameters();
    Adam& adam = runner.adam();
    Counters c;
    const bool validation = learner.has_validation();

    const std::string& path = o.checkpoint_path;
    if (!path.empty() && std::filesystem::exists(path)) {
        refuse_foreign_checkpoint(path, o, fingerprint);
        const std::string reason = o.resume ? read_checkpoint(path, fingerprint, learner, params, adam, c)
                                            : "resume is off (training from scratch as asked)";
        if (reason.empty()) {
            summary.resumed = true;
            log_info("%s: resuming from checkpoint %s at epoch %d", o.label.c_str(), path.c_str(), c.epoch);
        } else {
            summary.checkpoint_refused = reason;
            set_aside_checkpoint(path, reason);
        }
    }

    // The wall-clock budget and the reported time count the earlier processes' training too.
    const double seconds_before = c.seconds;
    const auto seconds = [&] { return seconds_before + timer.seconds(); };
    int last_saved = c.epoch;
    auto checkpoint = [&] {
        if (path.empty()) return;
        c.seconds = seconds();
        write_checkpoint(path, trainer_of(o), fingerprint, learner, params, adam, c);
        last_saved = c.epoch;
    };
    auto early_stop = [&] { return validation && o.patience > 0 && c.epochs_since_improvement >= o.patience; };
    Progress progress(o.label + " epoch", o.epochs, o.progress ? 2.0 : 1e30, c.epoch);
    // SIGTERM or SIGINT (pre-emption, scancel, Ctrl-C) during training: finish the epoch,
    // checkpoint it and throw Stopped (core/stop_signal.hpp).
    const StopPoint stop_point;
    while (c.epoch < o.epochs && !early_stop()) {
        try {
            c.last_loss = runner.run(c.epoch);
        } catch (const NumericalError& e) {
            throw NumericalError(o.label + ": epoch " + std::to_string(c.epoch + 1) + " of " + std::to_string(o.epochs) +
                                 ": " + e.what());
        }
        ++c.epoch;
        const double val = validation ? learner.validation_loss() : 0.0;
        if (!std::isfinite(c.last_loss) || !std::isfinite(val))
            throw NumericalError(o.label + ": the loss became non-finite at epoch " + std::to_string(c.epoch) +
                                 " (try a smaller learning rate)");
        c.train_curve.push_back(c.last_loss);
        if (validation) c.validation_curve.push_back(val);
        if (validation) track_validation(learner, val, c);
        if (c.epoch % o.checkpoint_every == 0) checkpoint();
        if (o.progress) report_epoch(progress, c, validation, val);
        if (o.interrupt && o.interrupt(c.epoch)) {
            summary.interrupted = true;
            break;
        }
        if (const int signal = take_stop_signal()) {
            if (last_saved != c.epoch) checkpoint();
            const std::string message =
                o.label + ": stopped by " + signal_name(signal) + " after epoch " + std::to_string(c.epoch) + " of " +
                std::to_string(o.epochs) +
                (path.empty() ? " (no checkpoint file: a new run starts again from epoch 0)"
                              : "; checkpoint '" + path + "' written: the next run resumes from it");
            log_warn("%s", message.c_str());
            throw Stopped(signal, message);
        }
        if (o.max_seconds > 0.0 && seconds() > o.max_seconds) {
            summary.time_limited = c.epoch < o.epochs;
            break;
        }
    }
    summary.stopped_early = early_stop() && c.epoch < o.epochs;
    if (!summary.interrupted && last_saved != c.epoch) checkpoint();
    if (validation && c.best_epoch > 0) learner.restore_best();

    summary.epochs_run = c.epoch;
    summary.best_epoch = c.best_epoch;
    summary.best_validation = c.best_validation;
    summary.final_loss = c.last_loss;
    summary.curve.stage = trainer_of(o);
    summary.curve.train_loss = c.train_curve;
    summary.curve.validation_loss = c.validation_curve;
    summary.seconds = seconds();
    summary.seconds_before = seconds_before;
    if (o.progress) {
        char extra[128];
        std::snprintf(extra, sizeof extra, "final loss %.6g%s%s", c.last_loss,
                      summary.time_limited ? " (time limit)" : "", summary.stopped_early ? " (stopped early)" : "");
        progress.finish(extra);
    }
    return summary;
}

} // namespace lb::nn
