#include "lb_paths.hpp"
#include "eval/experiment.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "eval/paper_numbers.hpp"
#include "eval/rollout.hpp"
#include "integrators/full_space_integrator.hpp"
#include "io/hdf5.hpp"
#include "io/table.hpp"
#include "io/toml_config.hpp"
#include "nn/inference_network.hpp"
#include "scene/scene.hpp"

namespace lb {
namespace fs = std::filesystem;

// ---------------------------------------------------------------- config ----
namespace {

std::string resolve(const std::string& path, const std::string& base)
{
    if (fs::path(path).is_absolute()) return path;
    if (fs::exists(fs::path(base) / path)) return (fs::path(base) / path).string();
    return (fs::path(LB_SOURCE_DIR) / path).string();
}

std::vector<Index> widths(ConfigTable& t, const std::string& key, const std::vector<Index>& fallback)
{
    std::vector<long long> w = t.get_int_array(key, {});
    if (!t.has(key)) return fallback;
    if (w.empty()) t.fail(key, "needs at least one width");
    std::vector<Index> out;
    for (long long v : w) {
        if (v <= 0) t.fail(key, "widths must be positive");
        out.push_back(Index(v));
    }
    return out;
}

void read_autoencoder(ConfigTable t, AutoencoderOptions& o, bool& latent_given)
{
    if (t.has("latent")) {
        o.latent_dim = Index(t.get_int("latent", 0));
        latent_given = true;
        if (o.latent_dim < 1) t.fail("latent", "must be at least 1");
    }
    o.hidden = widths(t, "hidden", o.hidden);
    o.pca_dim = Index(t.get_int("pca", o.pca_dim));
    o.epochs = int(t.get_int("epochs", o.epochs));
    o.batch_size = int(t.get_int("batch", o.batch_size));
    o.learning_rate = t.get_double("learning_rate", o.learning_rate);
    o.patience = int(t.get_int("patience", o.patience));
    o.validation_fraction = t.get_double("validation", o.validation_fraction);
    o.batch_norm = t.get_bool("batch_norm", o.batch_norm);
    o.residual = t.get_bool("residual", o.residual);
    o.seed = std::uint64_t(t.get_int("seed", (long long)o.seed));
    if (o.epochs < 1) t.fail("epochs", "must be at least 1");
    if (o.batch_size < 2) t.fail("batch", "must be at least 2 (BatchNorm)");
    if (!(o.learning_rate > 0.0)) t.fail("learning_rate", "must be positive");
    if (o.pca_dim < 0) t.fail("pca", "must be non-negative");
    if (!(o.validation_fraction > 0.0 && o.validation_fraction < 1.0)) t.fail("validation", "must lie in (0, 1)");
    t.finish();
}

/// Training keys shared by [training], [scenes.training] and [[integrators]].
void read_training(ConfigTable& t, IntegratorTrainOptions& o, bool& hidden_given)
{
    if (t.has("hidden")) {
        o.hidden = widths(t, "hidden", o.hidden);
        hidden_given = true;
    }
    o.epochs = int(t.get_int("epochs", o.epochs));
    o.batch_size = int(t.get_int("batch", o.batch_size));
    o.learning_rate = t.get_double("learning_rate", o.learning_rate);
    o.max_seconds = t.get_double("max_seconds", o.max_seconds);
    o.noise_fraction = t.get_double("noise_fraction", o.noise_fraction);
    o.balancing_floor = t.get_double("balancing_floor", o.balancing_floor);
    o.penalty_weight = t.get_double("penalty_weight", o.penalty_weight);
    o.seed = std::uint64_t(t.get_int("seed", (long long)o.seed));
    if (o.epochs < 1) t.fail("epochs", "must be at least 1");
    if (o.batch_size < 1) t.fail("batch", "must be at least 1");
    if (!(o.learning_rate > 0.0)) t.fail("learning_rate", "must be positive");
    if (o.max_seconds < 0.0) t.fail("max_seconds", "must be non-negative");
    if (o.noise_fraction < 0.0) t.fail("noise_fraction", "must be non-negative");
    if (!(o.penalty_weight > 0.0)) t.fail("penalty_weight", "must be positive");
}

} // namespace

const std::vector<std::string>& experiment_stages()
{
    static const std::vector<std::string> stages{"simulate", "autoencoder", "integrators", "rollouts", "tables", "plots"};
    return stages;
}

ExperimentConfig load_experiment(const std::string& path)
{
    const toml::table root = parse_toml_file(path);
    ConfigTable cfg(root, "", path);
    const std::string base = fs::path(path).parent_path().string();
    ExperimentConfig ex;
    ex.source = path;
    ex.toml_text = to_toml_string(root);
    ex.name = cfg.require_string("name");
    ex.description = cfg.get_string("description", "");
    ex.output_dir = cfg.get_string("output_dir", "runs/" + ex.name);
    ex.threads = int(cfg.get_int("threads", 0));

    AutoencoderOptions ae_defaults;
    bool latent_default_given = false;
    if (auto t = cfg.table("autoencoder")) read_autoencoder(*t, ae_defaults, latent_default_given);
    IntegratorTrainOptions train_defaults;
    bool hidden_default_given = false;
    if (auto t = cfg.table("training")) {
        read_training(*t, train_defaults, hidden_default_given);
        t->finish();
    }

    // The methods compared on every scene.
    struct MethodTemplate {
        std::string name;
        toml::table overrides;
    };
    std::vector<IntegratorSpec> methods;
    std::vector<ConfigTable> method_tables = cfg.table_array("integrators");
    if (method_tables.empty()) cfg.fail("integrators", "at least one [[integrators]] entry is required");
    std::set<std::string> names;
    for (ConfigTable& t : method_tables) {
        IntegratorSpec m;
        m.name = t.require_string("name");
        if (m.name.empty() || m.name.find_first_of("/ \t") != std::string::npos) t.fail("name", "must be a non-empty word");
        if (m.name == "full_space") t.fail("name", "'full_space' is reserved for the reference simulator");
        if (!names.insert(m.name).second) t.fail("name", "duplicate integrator name '" + m.name + "'");
        const std::string method = t.get_string("method", "latent_mlp");
        if (method == "linear_pca") {
            // Newton in a linear PCA subspace: no network, no training options.
            m.kind = MethodKind::LinearPca;
            m.linear_pca.dim = Index(t.get_int("dim", 0));
            m.linear_pca.penalty_weight = t.get_double("penalty_weight", m.linear_pca.penalty_weight);
            if (m.linear_pca.dim < 0) t.fail("dim", "must be positive (or omitted: the scene's latent size)");
            if (!(m.linear_pca.penalty_weight > 0.0)) t.fail("penalty_weight", "must be positive");
            t.finish();
            methods.push_back(m);
            continue;
        }
        if (method != "latent_mlp") t.fail("method", "unknown method '" + method + "' (latent_mlp or linear_pca)");
        m.options = train_defaults;
        m.hidden_given = hidden_default_given;
        m.options.loss = integrator_loss_from_string(t.get_string("loss", "self_supervised"));
        m.options.training_noise = t.get_bool("noise", true);
        m.options.data_balancing = t.get_bool("balancing", true);
        read_training(t, m.options, m.hidden_given);
        t.finish();
        methods.push_back(m);
    }

    for (ConfigTable s : cfg.table_array("scenes")) {
        SceneSpec sc;
        sc.scene_path = resolve(s.require_string("scene"), base);
        if (!fs::exists(sc.scene_path)) s.fail("scene", "file '" + sc.scene_path + "' does not exist");
        sc.variant = s.get_string("variant", "");
        sc.label = s.get_string("label", fs::path(sc.scene_path).stem().string() + (sc.variant.empty() ? "" : "_" + sc.variant));
        sc.autoencoder = ae_defaults;
        sc.latent_given = latent_default_given;
        if (auto t = s.table("autoencoder")) read_autoencoder(*t, sc.autoencoder, sc.latent_given);
        IntegratorTrainOptions scene_training = train_defaults;
        bool scene_hidden = hidden_default_given;
        std::optional<ConfigTable> scene_train = s.table("training");
        if (scene_train) {
            read_training(*scene_train, scene_training, scene_hidden);
            scene_train->finish();
        }
        for (IntegratorSpec m : methods) {
            // Scene-level [scenes.training] applies under each method's own switches
            // (loss, noise, balancing) and explicit overrides.
            if (scene_train && m.kind == MethodKind::LatentMlp) {
                const IntegratorSpec own = m;
                m.options = scene_training;
                m.options.loss = own.options.loss;
                m.options.training_noise = own.options.training_noise;
                m.options.data_balancing = own.options.data_balancing;
                m.hidden_given = scene_hidden || own.hidden_given;
                if (own.hidden_given && !scene_hidden) m.options.hidden = own.options.hidden;
            }
            sc.integrators.push_back(m);
        }
        s.finish();
        ex.scenes.push_back(sc);
    }
    if (ex.scenes.empty()) cfg.fail("scenes", "at least one [[scenes]] entry is required");

    if (auto t = cfg.table("evaluation")) {
        ex.sequences = t->get_string("sequences", ex.sequences);
        ex.rollout_frames = int(t->get_int("frames", 0));
        ex.full_space = t->get_bool("full_space", ex.full_space);
        if (ex.rollout_frames < 0) t->fail("frames", "must be non-negative");
        t->finish();
    }
    if (auto t = cfg.table("outputs")) {
        ex.plots = t->get_bool("plots", ex.plots);
        ex.filmstrips = t->get_bool("filmstrips", ex.filmstrips);
        ex.paper_tables = t->get_bool("paper_tables", ex.paper_tables);
        t->finish();
    }
    for (ConfigTable a : cfg.table_array("ablations")) {
        AblationSpec ab;
        ab.name = a.require_string("name");
        ab.title = a.get_string("title", ab.name);
        ab.methods = a.get_string_array("methods", {});
        for (const auto& m : ab.methods) {
            if (!names.count(m)) a.fail("methods", "unknown integrator '" + m + "'");
        }
        if (ab.methods.size() < 2) a.fail("methods", "an ablation compares at least two integrators");
        a.finish();
        ex.ablations.push_back(ab);
    }
    cfg.finish();
    return ex;
}

// -------------------------------------------------------------- pipeline ----
namespace {

std::string hash_hex(const std::string& text)
{
    std::uint64_t h = 1469598103934665603ull;  // FNV-1a 64
    for (unsigned char c : text) {
        h ^= c;
        h *= 1099511628211ull;
    }
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)h);
    return buf;
}

std::string read_key(const std::string& file)
{
    std::ifstream in(file + ".key");
    std::string key;
    std::getline(in, key);
    return key;
}

void write_key(const std::string& file, const std::string& key)
{
    h5::AtomicOutput out(file + ".key");
    std::ofstream(out.temp_path()) << key << "\n";
    out.commit();
}

/// Runs `work` unless `file` exists with a matching key and the stage is not forced.
class StageCache {
public:
    explicit StageCache(const RunOptions& options) : m_options(options) { }
    template <typename F>
    void run(const std::string& stage, const std::string& what, const std::string& file, const std::string& key, F&& work)
    {
        const bool forced = m_options.force.count(stage) || m_options.force.count("all");
        if (!forced && fs::exists(file) && read_key(file) == key) {
            log_info("[%s] %s: cached (%s)", stage.c_str(), what.c_str(), file.c_str());
            ++cached;
            return;
        }
        log_info("[%s] %s ...", stage.c_str(), what.c_str());
        Timer t;
        fs::remove(file + ".key");
        work();
        write_key(file, key);
        log_info("[%s] %s: done in %.1f s", stage.c_str(), what.c_str(), t.seconds());
        ++ran;
    }
    int ran = 0, cached = 0;

private:
    const RunOptions& m_options;
};

struct MethodResult {
    std::string name;
    MethodKind kind = MethodKind::LatentMlp;
    Index linear_pca_dim = 0;
    std::string rollout_file;
    std::vector<RolloutSummary> summaries;  ///< one per evaluated sequence
    IntegratorTrainOptions options;
    double train_seconds = 0.0;
};

struct SceneResult {
    SceneSpec spec;
    std::string dataset_file;
    std::string scene_name;
    Index dofs = 0;
    Index latent = 0;
    int train_frames = 0;
    double full_space_ms = 0.0;  ///< median Newton step of the dataset
    double jvp_ms = 0.0;         ///< one-vertex JVP through the decoder (float)
    std::string decoder_layers;
    std::vector<MethodResult> methods;
};

std::string widths_text(const std::vector<Index>& w)
{
    std::string s;
    for (size_t i = 0; i < w.size(); ++i) s += (i ? ", " : "") + std::to_string(w[i]);
    return s;
}

std::string autoencoder_key(const AutoencoderOptions& o)
{
    std::ostringstream s;
    s << o.latent_dim << "|" << widths_text(o.hidden) << "|" << o.pca_dim << "|" << o.batch_norm << o.residual << "|"
      << o.epochs << "|" << o.batch_size << "|" << o.learning_rate << "|" << o.validation_fraction << "|" << o.patience
      << "|" << o.seed;
    return s.str();
}

double median_of(std::vector<double> v)
{
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/// Median time (ms) of the Jacobian rows of one vertex's three outputs through the
/// float decoder (Table 2's "Computing JVP" column).
double measure_jvp_ms(Autoencoder& ae)
{
    nn::InferenceNetwork net(ae.decoder());
    const Index F = net.out_features();
    const Index v = (F / 3) / 2;
    const std::vector<Index> rows{3 * v, 3 * v + 1, 3 * v + 2};
    Eigen::VectorXf z = Eigen::VectorXf::Constant(net.in_features(), 0.1f);
    Eigen::MatrixXf J(3, net.in_features());
    std::vector<double> times;
    for (int i = 0; i < 220; ++i) {
        Timer t;
        net.jacobian_rows(z, rows, J);
        if (i >= 20) times.push_back(t.seconds());
    }
    return 1e3 * median_of(times);
}

RolloutSummary mean_summary(const std::vector<RolloutSummary>& all) { return aggregate(all); }

TableCell number(double v, int digits = 3)
{
    return std::isfinite(v) ? TableCell::significant(v, digits) : TableCell::missing("nan");
}

Table comparison_table(const SceneResult& r, const std::vector<std::string>& only, const std::string& title)
{
    Table t;
    t.title = title;
    t.caption = "Rollouts of every method on the test sequences of " + r.spec.label + " (" +
                std::to_string(r.dofs) + " DOF, latent " + std::to_string(r.latent) +
                "), from the first two ground-truth frames. Stable = frames before a NaN, RMSE > 0.5 or boundary "
                "violation > 0.1 (relative to the bounding-box diagonal); RMSE relative to the same diagonal; "
                "residual = ||∇E|| on free DOFs / force scale; times are medians per frame.";
    t.columns = {"method", "loss", "noise", "balancing"};
    for (const auto& title : summary_table_columns()) t.columns.push_back(title);
    for (const auto& m : r.methods) {
        if (!only.empty() && std::find(only.begin(), only.end(), m.name) == only.end()) continue;
        const RolloutSummary s = mean_summary(m.summaries);
        const bool untrained = m.name == "full_space" || m.kind != MethodKind::LatentMlp;
        const std::string loss = m.kind == MethodKind::LinearPca ? "— (linear PCA, d = " + std::to_string(m.linear_pca_dim) + ")"
                                 : untrained                     ? "—"
                                                                 : to_string(m.options.loss);
        std::vector<TableCell> cells{m.name, loss, untrained ? "—" : (m.options.training_noise ? "on" : "off"),
                                     untrained ? "—" : (m.options.data_balancing ? "on" : "off")};
        for (auto& c : summary_table_cells(s)) cells.push_back(std::move(c));
        t.add_row(std::move(cells));
    }
    t.add_note("training horizon: " + std::to_string(r.train_frames) + " frames per sequence");
    t.add_provenance();
    return t;
}

} // namespace

RunResult run_experiment(const ExperimentConfig& ex, const RunOptions& options)
{
    Timer total;
    for (const auto& f : options.force) {
        const auto& st = experiment_stages();
        if (f != "all" && std::find(st.begin(), st.end(), f) == st.end()) {
            throw ConfigError("--force: unknown stage '" + f + "' (stages: simulate, autoencoder, integrators, rollouts, tables, plots, all)");
        }
    }
    if (ex.threads > 0) set_num_threads(ex.threads);
    RunResult result;
    result.run_dir = options.output_dir.empty() ? ex.output_dir : options.output_dir;
    if (fs::path(result.run_dir).is_relative()) result.run_dir = (fs::current_path() / result.run_dir).string();
    fs::create_directories(result.run_dir);
    set_log_file(result.run_dir + "/run.log");
    log_info("experiment '%s' -> %s (log: run.log)", ex.name.c_str(), result.run_dir.c_str());
    {
        std::ofstream(result.run_dir + "/experiment.toml") << ex.toml_text;
    }
    StageCache cache(options);
    std::vector<SceneResult> scenes;

    for (const SceneSpec& spec : ex.scenes) {
        SceneResult r;
        r.spec = spec;
        const std::string dir = result.run_dir + "/" + spec.label;
        fs::create_directories(dir + "/integrators");
        fs::create_directories(dir + "/rollouts");
        const Scene scene = load_scene(spec.scene_path, {spec.variant});
        r.scene_name = scene.name;

        // simulate
        r.dataset_file = dir + "/data.h5";
        const std::string sim_key = hash_hex("simulate|" + scene.resolved_toml);
        cache.run("simulate", spec.label + ": full-space dataset", r.dataset_file, sim_key, [&] {
            SimulateOptions so;
            so.progress = log_level() >= LogLevel::Info;
            save_dataset(simulate_scene(scene, so), r.dataset_file);
        });
        const Dataset data = load_dataset(r.dataset_file);
        const PhysicsModel model(data.physics);
        r.dofs = model.num_dofs();
        r.train_frames = data.sequences.front().train_frames;
        std::vector<double> steps;
        for (const auto& s : data.sequences) {
            for (Index t = 1; t < s.num_frames(); ++t) steps.push_back(s.newton(t, 2));
        }
        r.full_space_ms = 1e3 * median_of(steps);

        // autoencoder
        AutoencoderOptions ao = spec.autoencoder;
        if (!spec.latent_given) ao.latent_dim = default_latent_dim(scene.name);
        ao.progress = log_level() >= LogLevel::Info;
        ao.checkpoint_path = dir + "/ae.checkpoint.h5";
        const std::string ae_file = dir + "/ae.h5";
        const std::string ae_key = hash_hex(sim_key + "|autoencoder|" + autoencoder_key(ao));
        cache.run("autoencoder", spec.label + ": autoencoder (latent " + std::to_string(ao.latent_dim) + ")", ae_file,
                  ae_key, [&] {
                      Autoencoder ae(data.physics, ao, ao.seed);
                      const AutoencoderTrainSummary s = train_autoencoder(ae, data, ao);
                      ae.set_scene_name(scene.name);
                      ae.save(ae_file);
                      log_info("%s: autoencoder validation relative RMSE %.3e", spec.label.c_str(), s.validation_relative_rmse);
                  });
        auto ae = std::make_shared<Autoencoder>(Autoencoder::load(ae_file, data.physics));
        r.latent = ae->latent_dim();
        r.decoder_layers = widths_text(ao.hidden) + (ao.pca_dim > 0 ? ", " + std::to_string(ao.pca_dim) : "");
        r.jvp_ms = measure_jvp_ms(*ae);
        const TrainingSamples samples = make_training_samples(*ae, data);
        // The evaluation protocol: the selected sequences, from their first two frames.
        std::vector<size_t> evaluated;
        try {
            evaluated = select_sequences(data, ex.sequences);
        } catch (const ConfigError& e) {
            throw ConfigError(ex.source + ": key 'evaluation.sequences' (" + spec.label + "): " + e.what());
        }
        auto roll_out = [&](Integrator& integrator) {
            RolloutOptions ro;
            ro.max_frames = ex.rollout_frames;
            std::vector<RolloutResult> rolls;
            for (size_t k : evaluated) rolls.push_back(rollout(integrator, model, data.sequences[k], ro));
            return rolls;
        };

        // Every method's rollouts: one cached stage per method, then its row.
        auto rollout_key = [&](const std::string& method_key) {
            return hash_hex(method_key + "|rollout|" + ex.sequences + "|" + std::to_string(ex.rollout_frames));
        };
        auto add_method = [&](MethodResult mr, const std::string& rkey,
                              const std::function<std::unique_ptr<Integrator>()>& make,
                              const std::function<void(const Integrator&)>& after = {}) {
            mr.rollout_file = dir + "/rollouts/" + mr.name + ".h5";
            cache.run("rollouts", spec.label + ": rollout '" + mr.name + "'", mr.rollout_file, rkey, [&] {
                const std::unique_ptr<Integrator> integrator = make();
                save_rollouts(roll_out(*integrator), mr.rollout_file, ex.toml_text);
                if (after) after(*integrator);
            });
            r.methods.push_back(std::move(mr));
        };

        // integrators and their rollouts
        for (const IntegratorSpec& m : spec.integrators) {
            MethodResult mr;
            mr.name = m.name;
            mr.kind = m.kind;
            const std::string file = dir + "/integrators/" + m.name + ".h5";
            if (m.kind == MethodKind::LinearPca) {
                LinearPcaOptions lo = m.linear_pca;
                if (lo.dim == 0) lo.dim = ae->latent_dim();
                std::ostringstream desc;
                desc << "linear_pca|dim=" << lo.dim << "|w_bc=" << lo.penalty_weight << "|it=" << lo.max_iterations
                     << "|tol=" << lo.gradient_tolerance << "," << lo.step_tolerance;
                const std::string key = hash_hex(sim_key + "|" + desc.str());
                cache.run("integrators", spec.label + ": linear PCA subspace '" + m.name + "' (d = " + std::to_string(lo.dim) + ")",
                          file, key, [&] { LinearPcaSubspace::fit(data, lo.dim).save(file); });
                const LinearPcaSubspace subspace = LinearPcaSubspace::load(file, data.physics);
                mr.linear_pca_dim = subspace.pca.dim();
                add_method(
                    mr, rollout_key(key),
                    [&] { return std::make_unique<LinearPcaIntegrator>(m.name, model, subspace, lo); },
                    [&](const Integrator& integrator) {
                        const auto& pca = static_cast<const LinearPcaIntegrator&>(integrator);
                        log_info("%s: linear PCA '%s': %.2f reduced Newton iterations per step", spec.label.c_str(),
                                 m.name.c_str(), pca.mean_iterations());
                        if (pca.unconverged_steps() > 0)
                            log_warn("%s: linear PCA '%s': %d reduced Newton solves stopped before converging",
                                     spec.label.c_str(), m.name.c_str(), pca.unconverged_steps());
                    });
                continue;
            }
            mr.options = m.options;
            if (!m.hidden_given) mr.options.hidden = default_integrator_hidden(scene.name);
            mr.options.progress = log_level() >= LogLevel::Info;
            mr.options.checkpoint_path = dir + "/integrators/" + m.name + ".checkpoint.h5";
            const std::string key = hash_hex(ae_key + "|integrator|" + mr.options.describe() + "|" +
                                             std::to_string(mr.options.epochs) + "|" + std::to_string(mr.options.max_seconds) +
                                             "|" + std::to_string(mr.options.noise_fraction) + "|" +
                                             std::to_string(mr.options.balancing_floor) + "|" +
                                             std::to_string(mr.options.penalty_weight));
            cache.run("integrators", spec.label + ": integrator '" + m.name + "' (" + mr.options.describe() + ")", file, key, [&] {
                LatentMlpModel net = LatentMlpModel::create(ae->latent_dim(), samples.p.rows(), mr.options.hidden, mr.options.seed);
                IntegratorTrainer trainer(model, *ae, mr.options);
                const IntegratorTrainSummary s = trainer.train(net, samples);
                h5::AtomicOutput out(file);
                {
                    h5::File f = h5::File::create(out.temp_path());
                    net.save(f, "integrator.");
                    f.set_attribute("/", "scene", scene.name);
                    f.set_attribute("/", "epochs_run", (long long)s.epochs_run);
                    f.set_attribute("/", "final_loss", s.final_loss);
                    f.set_attribute("/", "train_seconds", s.seconds);
                    f.set_attribute("/", "experiment", ex.toml_text);
                }
                out.commit();
            });
            add_method(mr, rollout_key(key), [&] {
                const h5::File f = h5::File::open(file);
                return std::make_unique<LatentMlpIntegrator>(m.name, ae, LatentMlpModel::load(f, "integrator."));
            });
        }
        if (ex.full_space) {
            MethodResult mr;
            mr.name = "full_space";
            add_method(mr, hash_hex(sim_key + "|full_space|" + ex.sequences + "|" + std::to_string(ex.rollout_frames)),
                       [&] { return std::make_unique<FullSpaceIntegrator>(model, scene.newton); });
        }
        // Summaries back from the rollout files (cached or fresh alike).
        for (MethodResult& mr : r.methods) {
            for (const RolloutRecord& rec : load_rollout_summaries(mr.rollout_file)) mr.summaries.push_back(rec.summary);
        }
        scenes.push_back(std::move(r));
    }

    // tables (cheap: always regenerated from the rollout files)
    const std::string tables_dir = result.run_dir + "/tables";
    fs::create_directories(tables_dir);
    auto emit = [&](const Table& t, const std::string& stem) {
        const auto files = write_table_files(t, tables_dir + "/" + stem);
        result.tables.push_back(files.front());
    };
    for (const SceneResult& r : scenes) {
        emit(comparison_table(r, {}, "Methods on " + r.spec.label), "methods_" + r.spec.label);
        for (const AblationSpec& ab : ex.ablations) {
            emit(comparison_table(r, ab.methods, ab.title + " (" + r.spec.label + ")"), "ablation_" + ab.name + "_" + r.spec.label);
        }
    }
    if (ex.paper_tables) {
        // Table 1: timings against the full-space simulation, ours beside the paper's.
        Table t1;
        t1.title = "Table 1: latent integration vs full-space simulation";
        t1.caption = "Per-frame times (median). 'ours' is the first self-supervised integrator of the suite, float, "
                     "batch 1, one thread; 'simulation' is the median full-space Newton step of the dataset. "
                     "Paper columns: Li et al. 2025, Table 1 (AMD Threadripper workstation).";
        t1.columns = {"example", "DOF", "latent", "simulation (ms)", "integration (ms)", "decoder (ms)", "total (ms)",
                      "paper DOF", "paper simulation (ms)", "paper integration (ms)", "paper decoder (ms)", "paper total (ms)"};
        Table t2;
        t2.title = "Table 2: our step vs one vertex's decoder JVP";
        t2.caption = "Computing JVP = the Jacobian rows of one vertex's three coordinates w.r.t. the latent through "
                     "the float decoder (the least an optimisation-based latent integrator such as Fulton et al. 2019 "
                     "needs per cubature point and iteration). Paper columns: Li et al. 2025, Table 2.";
        t2.columns = {"example", "DOF", "latent", "decoder layers", "integrator layers", "JVP (ms)", "ours (ms)",
                      "paper decoder layers", "paper integrator layers", "paper JVP (ms)", "paper ours (ms)"};
        for (const SceneResult& r : scenes) {
            const MethodResult* ours = nullptr;
            for (const auto& m : r.methods) {
                if (m.kind == MethodKind::LatentMlp && m.name != "full_space" && m.options.loss == IntegratorLoss::SelfSupervised) {
                    ours = &m;
                    break;
                }
            }
            if (!ours) continue;
            const RolloutSummary s = mean_summary(ours->summaries);
            const PaperTable1Row* p1 = find_paper_table1_row(r.scene_name);
            const PaperTable2Row* p2 = find_paper_table2_row(r.scene_name);
            auto paper = [](bool have, double v) { return have ? TableCell::significant(v, 4) : TableCell::missing(); };
            t1.add_row({r.spec.label, TableCell::integer(r.dofs), TableCell::integer(r.latent), number(r.full_space_ms, 4),
                        number(s.integrate_ms, 3), number(s.decode_ms, 3), number(s.total_ms, 3),
                        p1 ? TableCell::integer(p1->full_dofs) : TableCell::missing(), paper(p1, p1 ? p1->simulation_ms : 0),
                        paper(p1, p1 ? p1->integration_ms : 0), paper(p1, p1 ? p1->decoder_ms : 0),
                        paper(p1, p1 ? p1->total_ms : 0)});
            t2.add_row({r.spec.label, TableCell::integer(r.dofs), TableCell::integer(r.latent), r.decoder_layers,
                        widths_text(ours->options.hidden), number(r.jvp_ms, 3), number(s.total_ms, 3),
                        p2 ? TableCell(format_layers(p2->decoder_layers)) : TableCell::missing(),
                        p2 ? TableCell(format_layers(p2->integrator_layers)) : TableCell::missing(),
                        paper(p2, p2 ? p2->jvp_ms : 0), paper(p2, p2 ? p2->ours_ms : 0)});
        }
        t1.add_provenance();
        t2.add_provenance();
        if (!t1.rows.empty()) emit(t1, "table1_timings");
        if (!t2.rows.empty()) emit(t2, "table2_jvp");
    }
    log_info("[tables] %zu tables in %s", result.tables.size(), tables_dir.c_str());

    // plots (matplotlib scripts, Debian interpreter)
    if (ex.plots) {
        const std::string fig_dir = result.run_dir + "/figures";
        fs::create_directories(fig_dir);
        const std::string python = "/usr/bin/python3";
        if (!fs::exists(python)) throw Error("plots need " + python + " with matplotlib, h5py and numpy (scripts/run setup installs them)");
        for (const SceneResult& r : scenes) {
            std::string files;
            for (const auto& m : r.methods) files += " '" + m.rollout_file + "'";
            const std::string list = fig_dir + "/" + r.spec.label + ".txt";
            const std::string cmd = python + " '" + std::string(LB_SOURCE_DIR) + "/scripts/plot_rollouts.py'" + files +
                                    " -o '" + fig_dir + "/" + r.spec.label + "' --title '" + r.spec.label +
                                    "' --train-frames " + std::to_string(r.train_frames) + " > '" + list + "' 2>> '" +
                                    result.run_dir + "/run.log'";
            if (std::system(cmd.c_str()) != 0) throw Error("plotting failed for " + r.spec.label + " (see " + result.run_dir + "/run.log)");
            std::ifstream in(list);
            for (std::string line; std::getline(in, line);) {
                if (line.size() > 4 && line.substr(line.size() - 4) == ".png") result.figures.push_back(line);
            }
            fs::remove(list);
            if (ex.filmstrips) {
                std::string rolls;
                for (const auto& m : r.methods) {
                    if (m.name != "full_space") rolls += " '" + m.rollout_file + "'";
                }
                const std::string png = fig_dir + "/" + r.spec.label + "_filmstrip.png";
                const std::string fcmd = python + " '" + std::string(LB_SOURCE_DIR) + "/scripts/plot_filmstrip.py' '" +
                                         r.dataset_file + "'" + rolls + " -o '" + png + "' >> '" + result.run_dir +
                                         "/run.log' 2>&1";
                if (std::system(fcmd.c_str()) != 0) throw Error("filmstrip failed for " + r.spec.label + " (see " + result.run_dir + "/run.log)");
                result.figures.push_back(png);
            }
        }
        log_info("[plots] %zu figures in %s", result.figures.size(), fig_dir.c_str());
    }
    result.stages_run = cache.ran;
    result.stages_cached = cache.cached;
    result.seconds = total.seconds();
    log_info("experiment '%s' finished in %.1f s: %d stages run, %d cached", ex.name.c_str(), result.seconds,
             result.stages_run, result.stages_cached);
    set_log_file("");
    return result;
}

} // namespace lb
