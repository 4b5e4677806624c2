#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/log.hpp"
#include "core/parse.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "eval/rollout.hpp"
#include "io/hdf5.hpp"
#include "methods/artefact.hpp"
#include "methods/full_space/full_space_method.hpp"
#include "nn/inference_network.hpp"
#include "paper/scene_defaults.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/plots.hpp"
#include "pipeline/report.hpp"
#include "pipeline/stage_cache.hpp"
#include "scene/scene.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

/// Every resolved autoencoder option that changes the trained network.
std::string autoencoder_key(const AutoencoderOptions& o)
{
    std::ostringstream s;
    s << o.latent_dim << "|" << format_list(o.hidden) << "|" << o.pca_dim << "|" << o.batch_norm << o.residual << "|"
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
    constexpr int kWarmup = 20, kRepeats = 200;
    nn::InferenceNetwork net(ae.decoder());
    const Index v = (net.out_features() / 3) / 2;
    const std::vector<Index> rows{3 * v, 3 * v + 1, 3 * v + 2};
    Eigen::VectorXf z = Eigen::VectorXf::Constant(net.in_features(), 0.1f);
    Eigen::MatrixXf J(3, net.in_features());
    std::vector<double> times;
    for (int i = 0; i < kWarmup + kRepeats; ++i) {
        Timer t;
        net.jacobian_rows(z, rows, J);
        if (i >= kWarmup) times.push_back(t.seconds());
    }
    return 1e3 * median_of(times);
}

/// The stages of one scene and what the tables need from them.
class SceneRun {
public:
    SceneRun(const ExperimentConfig& ex, const SceneSpec& spec, StageCache& cache, const std::string& run_dir)
        : m_ex(ex), m_spec(spec), m_cache(cache), m_dir(run_dir + "/" + spec.label),
          m_scene(load_scene(spec.scene_path, {spec.variant}))
    {
        fs::create_directories(m_dir + "/integrators");
        fs::create_directories(m_dir + "/rollouts");
        m_result.label = spec.label;
        m_result.scene_name = m_scene.name;
    }

    SceneResult run()
    {
        simulate();
        train_autoencoder_stage();
        m_evaluated = select_evaluated();
        for (const MethodSpec& m : m_spec.methods) {
            m.method->resolve({m_scene.name, m_ae->latent_dim()});
            if (!m_ex.seeds.empty() && m.method->set_seed(m_ex.seeds.front())) {
                run_seeds(m.name, *m.method);
            } else {
                m_result.methods.push_back(run_method(m.name, m.name, *m.method));
            }
        }
        if (m_ex.full_space) {
            const std::unique_ptr<Method> reference = builtin_full_space();
            m_result.methods.push_back(run_method("full_space", "full_space", *reference));
        }
        return std::move(m_result);
    }

private:
    void simulate()
    {
        m_result.dataset_file = m_dir + "/data.h5";
        m_sim_key = fnv1a64_hex("simulate|" + m_scene.resolved_toml);
        m_cache.run("simulate", m_spec.label + ": full-space dataset", m_result.dataset_file, m_sim_key, [&] {
            SimulateOptions so;
            so.progress = log_level() >= LogLevel::Info;
            save_dataset(simulate_scene(m_scene, so), m_result.dataset_file);
        });
        m_data = load_dataset(m_result.dataset_file);
        m_model = std::make_unique<PhysicsModel>(m_data.physics);
        m_result.dofs = m_model->num_dofs();
        m_result.train_frames = m_data.sequences.front().train_frames;
        std::vector<double> steps;
        for (const auto& s : m_data.sequences) {
            for (Index t = 1; t < s.num_frames(); ++t) steps.push_back(s.newton(t, 2));
        }
        m_result.dataset_step_ms = 1e3 * median_of(steps);
    }

    void train_autoencoder_stage()
    {
        AutoencoderOptions ao = m_spec.autoencoder;
        if (!m_spec.latent_given) ao.latent_dim = default_latent_dim(m_scene.name);
        ao.progress = log_level() >= LogLevel::Info;
        ao.checkpoint_path = m_dir + "/ae.checkpoint.h5";
        ao.resume = !m_cache.forced("autoencoder");
        const std::string file = m_dir + "/ae.h5";
        m_ae_key = fnv1a64_hex(m_sim_key + "|autoencoder|" + autoencoder_key(ao));
        m_cache.run("autoencoder", m_spec.label + ": autoencoder (latent " + std::to_string(ao.latent_dim) + ")", file,
                    m_ae_key, [&] {
                        Autoencoder ae(m_data.physics, ao, ao.seed);
                        const AutoencoderTrainSummary s = train_autoencoder(ae, m_data, ao);
                        ae.set_scene_name(m_scene.name);
                        ae.save(file);
                        log_info("%s: autoencoder validation relative RMSE %.3e", m_spec.label.c_str(),
                                 s.validation_relative_rmse);
                    });
        m_ae = std::make_shared<Autoencoder>(Autoencoder::load(file, m_data.physics));
        m_result.latent = m_ae->latent_dim();
        m_result.decoder_layers = format_list(ao.hidden) + (ao.pca_dim > 0 ? ", " + std::to_string(ao.pca_dim) : "");
        m_result.jvp_ms = measure_jvp_ms(*m_ae);
    }

    std::vector<size_t> select_evaluated() const
    {
        try {
            return select_sequences(m_data, m_ex.sequences);
        } catch (const ConfigError& e) {
            throw ConfigError(m_ex.source + ": key 'evaluation.sequences' (" + m_spec.label + "): " + e.what());
        }
    }

    static std::unique_ptr<Method> builtin_full_space()
    {
        const toml::table empty;
        ConfigTable entry(empty, "", "full_space"), defaults(empty, "", "full_space");
        return full_space_method().parse(entry, defaults);
    }

    /// A learned method once per seed of the suite: one table row with per-seed summaries
    /// (files <name>.seed<k>.h5; the figures show the first seed's rollout).
    void run_seeds(const std::string& name, Method& method)
    {
        MethodResult combined;
        for (const std::uint64_t seed : m_ex.seeds) {
            method.set_seed(seed);
            MethodResult r = run_method(name, name + ".seed" + std::to_string(seed), method);
            if (combined.name.empty()) {
                combined = r;
                combined.summaries.clear();
            }
            combined.summaries.insert(combined.summaries.end(), r.summaries.begin(), r.summaries.end());
            combined.seeds.push_back(seed);
            combined.per_seed.push_back(aggregate(r.summaries));
            combined.budgets.push_back(r.budgets.front());
        }
        m_result.methods.push_back(std::move(combined));
    }

    /// The training budget and how it ended, from a learned method's artefact attributes
    /// ("" if it records none).
    static TrainingBudget read_budget(const std::string& artefact)
    {
        TrainingBudget b;
        const h5::File f = h5::File::open(artefact);
        if (!f.has_attribute("/", "epochs_run")) return b;
        b.recorded = true;
        b.epochs_run = f.attribute_int("/", "epochs_run");
        if (f.has_attribute("/", "epochs_budget")) b.epochs_budget = f.attribute_int("/", "epochs_budget");
        if (f.has_attribute("/", "train_seconds")) b.seconds = f.attribute_double("/", "train_seconds");
        if (f.has_attribute("/", "max_seconds")) b.max_seconds = f.attribute_double("/", "max_seconds");
        if (f.has_attribute("/", "time_limited")) b.time_limited = f.attribute_int("/", "time_limited") != 0;
        if (f.has_attribute("/", "stopped_early")) b.stopped_early = f.attribute_int("/", "stopped_early") != 0;
        return b;
    }

    /// Fit (if the method has an artefact) and roll out one method: two cached stages.
    /// @param name  the label in tables;  @param stem  its file names (name, or name.seed<k>)
    MethodResult run_method(const std::string& name, const std::string& stem, Method& method)
    {
        method.resolve({m_scene.name, m_ae->latent_dim()});
        MethodInputs in;
        in.data = &m_data;
        in.model = m_model.get();
        if (method.needs_autoencoder()) in.autoencoder = m_ae;
        in.checkpoint_path = m_dir + "/integrators/" + stem + ".checkpoint.h5";
        in.resume = !m_cache.forced("integrators");
        in.progress = log_level() >= LogLevel::Info;
        in.newton = m_scene.newton;
        const std::string inputs_key = method.needs_autoencoder() ? m_ae_key : m_sim_key;
        const std::string key = fnv1a64_hex(inputs_key + "|" + method.method_name() + "|" + method.options_text());
        const std::string artefact = m_dir + "/integrators/" + stem + ".h5";
        if (method.has_artefact()) {
            m_cache.run("integrators", m_spec.label + ": fit '" + stem + "' (" + method.method_name() + ": " +
                                           method.summary() + ")",
                        artefact, key, [&] { fit_artefact(method, in, m_scene.name, artefact, m_ex.toml_text); });
        }
        MethodResult mr;
        mr.name = name;
        mr.method = method.method_name();
        mr.summary = method.summary();
        mr.layers = method.layers();
        mr.paper_method = method.is_paper_method();
        mr.rollout_file = m_dir + "/rollouts/" + stem + ".h5";
        mr.budgets.push_back(method.has_artefact() ? read_budget(artefact) : TrainingBudget{});
        if (method.has_artefact()) mr.embeddings = load_embedding_metrics(h5::File::open(artefact));
        const std::string rkey = fnv1a64_hex(key + "|rollout|" + m_ex.sequences + "|" + std::to_string(m_ex.rollout_frames) +
                                              "|format " + std::to_string(kRolloutFormatVersion));
        mr.rollout_key = rkey;
        m_cache.run("rollouts", m_spec.label + ": rollout '" + stem + "'", mr.rollout_file, rkey, [&] {
            std::unique_ptr<Integrator> integrator;
            if (method.has_artefact()) {
                const h5::File f = h5::File::open(artefact);
                integrator = method.load(in, &f, stem);
            } else {
                integrator = method.load(in, nullptr, stem);
            }
            RolloutOptions ro;
            ro.max_frames = m_ex.rollout_frames;
            std::vector<RolloutResult> rolls;
            for (size_t k : m_evaluated) rolls.push_back(rollout(*integrator, *m_model, m_data.sequences[k], ro));
            save_rollouts(rolls, mr.rollout_file, m_ex.toml_text);
            const std::string line = method.after_rollout(*integrator);
            if (!line.empty()) log_info("%s: %s: %s", m_spec.label.c_str(), name.c_str(), line.c_str());
        });
        for (const RolloutRecord& rec : load_rollout_summaries(mr.rollout_file)) mr.summaries.push_back(rec.summary);
        return mr;
    }

    const ExperimentConfig& m_ex;
    const SceneSpec& m_spec;
    StageCache& m_cache;
    std::string m_dir;
    Scene m_scene;
    SceneResult m_result;
    Dataset m_data;
    std::unique_ptr<PhysicsModel> m_model;
    std::shared_ptr<Autoencoder> m_ae;
    std::string m_sim_key, m_ae_key;
    std::vector<size_t> m_evaluated;
};

} // namespace

RunResult run_experiment(const ExperimentConfig& ex, const RunOptions& options)
{
    Timer total;
    StageCache cache(options.force);
    if (ex.threads > 0) set_num_threads(ex.threads);
    RunResult result;
    result.run_dir = options.output_dir.empty() ? ex.output_dir : options.output_dir;
    if (fs::path(result.run_dir).is_relative()) result.run_dir = (fs::current_path() / result.run_dir).string();
    fs::create_directories(result.run_dir);
    set_log_file(result.run_dir + "/run.log");
    log_info("experiment '%s' -> %s (log: run.log)", ex.name.c_str(), result.run_dir.c_str());
    std::ofstream(result.run_dir + "/experiment.toml") << ex.toml_text;

    std::vector<SceneResult> scenes;
    for (const SceneSpec& spec : ex.scenes) scenes.push_back(SceneRun(ex, spec, cache, result.run_dir).run());

    result.tables = write_tables(ex, scenes, result.run_dir + "/tables");
    log_info("[tables] %zu tables in %s/tables", result.tables.size(), result.run_dir.c_str());
    if (ex.plots) {
        PlotOptions po;
        po.figures_dir = result.run_dir + "/figures";
        po.log_path = result.run_dir + "/run.log";
        po.filmstrips = ex.filmstrips;
        for (const SceneResult& r : scenes) {
            const std::vector<std::string> f = plot_scene(r, po);
            result.figures.insert(result.figures.end(), f.begin(), f.end());
        }
        log_info("[plots] %zu figures in %s", result.figures.size(), po.figures_dir.c_str());
    }
    if (ex.videos) {
        // A cached stage: the key covers every method's rollout (and so everything before
        // it) and the video length; --force videos redraws.
        for (const SceneResult& r : scenes) {
            VideoOptions vo;
            vo.output = result.run_dir + "/videos/" + r.label + ".mp4";
            vo.log_path = result.run_dir + "/run.log";
            vo.max_frames = ex.video_frames;
            std::string key = "video|" + std::to_string(vo.max_frames);
            for (const MethodResult& m : r.methods) key += "|" + m.name + "=" + m.rollout_key;
            cache.run("videos", r.label + ": video", vo.output, fnv1a64_hex(key), [&] { video_scene(r, vo); });
            result.videos.push_back(vo.output);
        }
        log_info("[videos] %zu videos in %s/videos", result.videos.size(), result.run_dir.c_str());
    }
    result.stages_run = cache.ran();
    result.stages_cached = cache.cached();
    result.seconds = total.seconds();
    log_info("experiment '%s' finished in %.1f s: %d stages run, %d cached", ex.name.c_str(), result.seconds,
             result.stages_run, result.stages_cached);
    set_log_file("");
    return result;
}

} // namespace lb
