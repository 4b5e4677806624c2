#include <unistd.h>

#include <algorithm>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/log.hpp"
#include "core/parse.hpp"
#include "core/parallel.hpp"
#include "core/stop_signal.hpp"
#include "core/timer.hpp"
#include "eval/diagnose.hpp"
#include "eval/rollout.hpp"
#include "io/atomic_file.hpp"
#include "io/hdf5.hpp"
#include "io/table_data.hpp"
#include "methods/artefact.hpp"
#include "nn/inference_network.hpp"
#include "pipeline/experiment.hpp"
#include "pipeline/html_page.hpp"
#include "pipeline/plan.hpp"
#include "pipeline/plots.hpp"
#include "pipeline/report.hpp"
#include "pipeline/stage_cache.hpp"
#include "pipeline/training_curves.hpp"
#include "scene/scene.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

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


/// A learned method's training budget and how it ended, from its artefact's attributes
/// (not recorded if the method records none).
TrainingBudget read_budget(const std::string& artefact)
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

/// What the units of one scene share once its scene unit has completed.
struct LoadedScene {
    Scene scene;
    Dataset data;
    std::unique_ptr<PhysicsModel> model;
    std::shared_ptr<Autoencoder> ae;
    AutoencoderOptions ae_options;
};

/// `<run_dir>/units/<id>.status` (unit_status_path): "running", "done", "failed" or
/// "stopped" (by SIGTERM or SIGINT at a safe point: the next run resumes it), then where
/// and when, then details. It tells a merge, and `latentbench status`, why a unit has no
/// outputs; the outputs' keys alone say whether it completed.
std::string status_path(const std::string& run_dir, const std::string& id) { return unit_status_path(run_dir, id); }

/// A status that could not be written (a full disk): the status file is renamed to
/// `<id>.status.unwritten-<status>`, which needs no free space, so that a merge can say
/// that the last status write failed instead of reading a stale "running".
std::string unwritten_path(const std::string& run_dir, const std::string& id, const std::string& status)
{
    return status_path(run_dir, id) + ".unwritten-" + status;
}

constexpr const char* kStatuses[] = {"running", "done", "failed", "stopped"};

/// Write the status atomically (io/atomic_file.hpp): the file holds the old status or the
/// new one, whole. If it cannot be written, mark that (unwritten_path) and rethrow.
void write_status(const std::string& run_dir, const std::string& id, const std::string& status, const std::string& detail)
{
    char host[256] = "?";
    gethostname(host, sizeof host - 1);
    const std::time_t now = std::time(nullptr);
    char date[64];
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S UTC", std::gmtime(&now));
    std::error_code ec;
    try {
        write_text_atomically(status_path(run_dir, id), status + "\n" + std::string(host) + " pid " +
                                                            std::to_string(getpid()) + " " + date + "\n" + detail + "\n");
    } catch (const Error&) {
        // A rename in the same directory: it works on a full disk, where writing does not.
        if (fs::exists(status_path(run_dir, id), ec))
            fs::rename(status_path(run_dir, id), unwritten_path(run_dir, id, status), ec);
        throw;
    }
    for (const char* s : kStatuses) fs::remove(unwritten_path(run_dir, id, s), ec);  // an earlier failure's mark
}

/// Runs units of a plan through the stage cache; loads each scene's dataset and
/// autoencoder once, and only from a scene unit that has completed.
class UnitRunner {
public:
    UnitRunner(const ExperimentConfig& ex, const ExperimentPlan& plan, StageCache& cache)
        : m_ex(ex), m_points(experiment_points(ex)), m_plan(plan), m_cache(cache)
    {
    }

    void run(const Unit& u)
    {
        for (const std::string& dep : u.depends_on) {
            const Unit* d = m_plan.find(dep);
            if (d && !unit_complete(*d) && contained(*d) && status_of(*d) == "failed") {
                // A Python method's failed fit: this unit fails too, recorded, so that the merge
                // leaves the row out instead of waiting for it (a Slurm array runs it anyway).
                write_status(m_plan.run_dir, u.id, "failed", "not run: unit '" + dep + "' failed");
                throw Error("unit '" + u.id + "' not run: unit '" + dep + "' failed");
            }
            if (!d || !unit_complete(*d))
                throw Error("unit '" + u.id + "' needs unit '" + dep + "', which has not completed (run `latentbench run " +
                            m_ex.source + " --unit " + dep + "` first)");
        }
        write_status(m_plan.run_dir, u.id, "running", "");
        try {
            // Each unit makes the directories it writes to: a fit or eval unit after the
            // user removed `integrators/` or `rollouts/` to redo them.
            for (const UnitOutput& o : u.outputs) fs::create_directories(fs::path(o.file).parent_path());
            switch (u.kind) {
            case UnitKind::Scene: run_scene(u); break;
            case UnitKind::Fit: run_fit(u); break;
            case UnitKind::Eval: run_eval(u); break;
            }
        } catch (const Stopped& e) {
            // Not a failure: the checkpoint is written and the next run resumes from it.
            try {
                write_status(m_plan.run_dir, u.id, "stopped", e.what());
            } catch (const Error&) {
                // The stop is what the caller must see; the merge reads the mark.
            }
            throw;
        } catch (const std::exception& e) {
            try {
                write_status(m_plan.run_dir, u.id, "failed", e.what());
            } catch (const Error& status_error) {
                // The unit's own error comes first; the status one is for the merge (marked).
                throw Error(std::string(e.what()) + "; moreover its status could not be written: " + status_error.what());
            }
            throw;
        }
        try {
            write_status(m_plan.run_dir, u.id, "done", "");
        } catch (const Error& e) {
            throw Error("unit '" + u.id + "' completed, but its status could not be written: " + e.what());
        }
    }

    /// A unit's recorded status ("" if none).
    std::string status_of(const Unit& u) const
    {
        const std::optional<UnitStatusRecord> r = read_unit_status(m_plan.run_dir, u.id);
        return r ? r->status : "";
    }

    /// True for a fit or eval unit of a method whose failures are contained (user code).
    bool contained(const Unit& u)
    {
        if (u.kind == UnitKind::Scene) return false;
        const Unit* su = m_plan.find(u.scene_unit);
        if (!su || !unit_complete(*su)) return false;
        return method_of(u, loaded(u.scene_unit)).failures_contained();
    }

    /// The tables' facts of one scene (its first scene unit) and every row of it but those
    /// with a unit in `failed` (id → why), which are named in r.failed_rows instead.
    SceneResult scene_result(size_t s, const std::map<std::string, std::string>& failed = {})
    {
        const Unit& su = *m_plan.find(m_plan.scene_units[s]);
        LoadedScene& ls = loaded(su.id);
        SceneResult r;
        r.label = su.scene;
        r.scene_name = ls.scene.name;
        r.dataset_file = su.outputs[0].file;
        r.dofs = ls.model->num_dofs();
        r.train_frames = ls.data.sequences.front().train_frames;
        std::vector<double> steps;
        for (const auto& q : ls.data.sequences) {
            for (Index t = 1; t < q.num_frames(); ++t) steps.push_back(q.newton(t, 2));
        }
        r.dataset_step_ms = 1e3 * median_of(steps);
        r.latent = ls.ae->latent_dim();
        const AutoencoderOptions& ao = ls.ae->options();  // as trained: the PCA width after clamping
        r.decoder_layers = format_list(ao.hidden) + (ao.pca_dim > 0 ? ", " + std::to_string(ao.pca_dim) : "");
        r.jvp_ms = measure_jvp_ms(*ls.ae);
        r.autoencoder_curves = nn::load_training_curves(h5::File::open(su.outputs[1].file), "");
        r.autoencoder_seed = ls.ae->seed();
        r.seed_scope = m_ex.seed_scope;
        for (const PlannedRow& row : m_plan.rows) {
            if (row.scene_index != s) continue;
            std::string why;
            for (const std::string& id : row.eval_units) {
                const Unit& eu = *m_plan.find(id);
                for (const std::string& unit_id : {eu.fit_unit, id}) {
                    const auto f = failed.find(unit_id);
                    if (why.empty() && !unit_id.empty() && f != failed.end()) why = unit_id + " " + f->second;
                }
            }
            if (why.empty()) r.methods.push_back(method_result(row));
            else r.failed_rows.push_back(row.name + ": " + why);
        }
        return r;
    }

    /// The error decomposition of scene `s` (README "Error decomposition") as a cached
    /// stage: the autoencoder's rows, then per table row (first seed) its one step from
    /// the truth (fulton_full: the manifold-optimal step) and its rollout. The key covers
    /// the dataset, the autoencoder, every rollout (and so every artefact) and the stride.
    /// Rows with a unit in `failed` (contained failures) are left out, as in the tables.
    std::vector<std::string> diagnose_scene(size_t s, const std::string& tables_dir,
                                            const std::map<std::string, std::string>& failed = {})
    {
        const Unit& su = *m_plan.find(m_plan.scene_units[s]);
        std::vector<const PlannedRow*> rows;
        std::string key = "diagnose|" + std::to_string(m_ex.diagnose_stride) + "|" + su.outputs[0].key + "|" +
                          su.outputs[1].key;
        for (const PlannedRow& row : m_plan.rows) {
            if (row.scene_index != s) continue;
            const bool row_failed = std::any_of(row.eval_units.begin(), row.eval_units.end(), [&](const std::string& id) {
                return failed.count(id) > 0 || failed.count(m_plan.find(id)->fit_unit) > 0;
            });
            if (row_failed) continue;
            rows.push_back(&row);
            key += "|" + row.name + "=" + m_plan.find(row.eval_units.front())->outputs[0].key;
        }
        // the manifold-optimal steps (fulton_full) first: they bound the one steps below them
        std::stable_partition(rows.begin(), rows.end(), [&](const PlannedRow* row) {
            const Unit& u = *m_plan.find(row->eval_units.front());
            return !u.full_space && gives_manifold_optimal_step(
                                        m_points[u.point_index]->scenes[u.scene_index].methods[u.method_index].method->method_name());
        });
        const std::string stem = tables_dir + "/diagnose_" + su.scene;
        m_cache.run("diagnose", su.scene + ": error decomposition", stem + ".md", fnv1a64_hex(key), [&] {
            LoadedScene& ls = loaded(su.id);
            DiagnoseOptions options;
            options.sequences = select_sequences(ls.data, m_points[su.point_index]->sequences);
            options.stride = m_ex.diagnose_stride;
            Diagnosis diagnosis(*ls.model, ls.data, options);
            diagnosis.add_autoencoder(*ls.ae);
            for (const PlannedRow* row : rows) {
                const Unit& u = *m_plan.find(row->eval_units.front());
                if (u.full_space) continue;  // the simulator that made the truth
                const std::string label = row->point_text.empty() ? row->name : row->name + " [" + row->point_text + "]";
                Method& method = method_of(u, ls);
                const MethodInputs in = inputs_of(u, ls, method);
                const std::unique_ptr<Integrator> integrator = load_integrator(u, method, in, label);
                log_info("%s: diagnose: one step from the truth with %s", su.scene.c_str(), label.c_str());
                diagnosis.add_one_step(*integrator, one_step_stage(method.method_name()));
                std::vector<RolloutRecord> records = load_rollout_summaries(u.outputs[0].file);
                for (RolloutRecord& r : records) r.method = label;
                diagnosis.add_rollout(records);
            }
            const Table table = diagnosis.table(ls.data.scene_name);
            write_table_files(table, stem);
            write_table_data(table, stem);
        });
        return {stem + ".md"};
    }

private:
    void run_scene(const Unit& u)
    {
        const SceneSpec& spec = m_points[u.point_index]->scenes[u.scene_index];
        LoadedScene& ls = m_loaded[u.id];
        ls.scene = load_scene(spec.scene_path, {spec.variant});
        const std::string& data_file = u.outputs[0].file;
        m_cache.run("simulate", u.scene + ": full-space dataset", data_file, u.outputs[0].key, [&] {
            // Another scene unit of this scene (a seed's under `[seeds] scope = "autoencoder"`, a
            // sweep point's) may already hold this very dataset: copy it rather than simulate again.
            for (const Unit& twin : m_plan.units) {
                if (twin.kind != UnitKind::Scene || twin.id == u.id || twin.outputs[0].key != u.outputs[0].key) continue;
                if (!unit_output_current(twin.outputs[0]) || m_cache.forced("simulate")) continue;
                log_info("%s: full-space dataset copied from %s (same simulation key)", u.scene.c_str(), twin.id.c_str());
                copy_file_atomically(twin.outputs[0].file, data_file);
                return;
            }
            SimulateOptions so;
            so.progress = log_level() >= LogLevel::Info;
            save_dataset(simulate_scene(ls.scene, so), data_file);
        });
        ls.data = load_dataset(data_file);
        ls.model = std::make_unique<PhysicsModel>(ls.data.physics);
        AutoencoderOptions ao = resolved_autoencoder(spec, ls.scene, u.seed);
        ao.progress = log_level() >= LogLevel::Info;
        ao.checkpoint_path = unit_checkpoint_path(u);
        ao.resume = !m_cache.forced("autoencoder");
        ls.ae_options = ao;
        const std::string& file = u.outputs[1].file;
        m_cache.run("autoencoder", u.scene + ": autoencoder (latent " + std::to_string(ao.latent_dim) + ")", file,
                    u.outputs[1].key, [&] {
                        Autoencoder ae(ls.data.physics, ao, ao.seed);
                        const AutoencoderTrainSummary s = train_autoencoder(ae, ls.data, ao);
                        ae.set_scene_name(ls.scene.name);
                        ae.save(file, s.curves);
                        if (s.physics_ran)
                            log_info("%s: autoencoder validation relative RMSE %.3e before the physics "
                                     "fine-tuning (held out), %.3e after it (trained on)",
                                     u.scene.c_str(), s.validation_relative_rmse_held_out,
                                     s.validation_relative_rmse);
                        else
                            log_info("%s: autoencoder validation relative RMSE %.3e", u.scene.c_str(),
                                     s.validation_relative_rmse);
                    });
        ls.ae = std::make_shared<Autoencoder>(Autoencoder::load(file, ls.data.physics));
    }

    /// The dataset and autoencoder of a completed scene unit (loaded once).
    LoadedScene& loaded(const std::string& scene_unit)
    {
        if (auto it = m_loaded.find(scene_unit); it != m_loaded.end() && it->second.ae) return it->second;
        const Unit* u = m_plan.find(scene_unit);
        if (!u || !unit_complete(*u)) throw Error("unit '" + scene_unit + "' has not completed");
        const SceneSpec& spec = m_points[u->point_index]->scenes[u->scene_index];
        LoadedScene& ls = m_loaded[scene_unit];
        ls.scene = load_scene(spec.scene_path, {spec.variant});
        ls.data = load_dataset(u->outputs[0].file);
        ls.model = std::make_unique<PhysicsModel>(ls.data.physics);
        ls.ae_options = resolved_autoencoder(spec, ls.scene, u->seed);
        ls.ae = std::make_shared<Autoencoder>(Autoencoder::load(u->outputs[1].file, ls.data.physics));
        return ls;
    }

    /// The unit's method, resolved for its scene and with its seed set.
    Method& method_of(const Unit& u, const LoadedScene& ls)
    {
        Method* method = nullptr;
        if (u.full_space) {
            if (!m_reference) m_reference = reference_method();
            method = m_reference.get();
        } else {
            method = m_points[u.point_index]->scenes[u.scene_index].methods[u.method_index].method.get();
        }
        method->resolve({ls.scene.name, ls.ae->latent_dim()});
        if (u.seed) method->set_seed(*u.seed);
        return *method;
    }

    MethodInputs inputs_of(const Unit& u, const LoadedScene& ls, const Method& method) const
    {
        MethodInputs in;
        in.data = &ls.data;
        in.model = ls.model.get();
        if (method.needs_autoencoder()) in.autoencoder = ls.ae;
        in.checkpoint_path = unit_checkpoint_path(u);
        in.resume = !m_cache.forced("integrators");
        in.progress = log_level() >= LogLevel::Info;
        in.newton = ls.scene.newton;
        const Unit& su = *m_plan.find(u.scene_unit);
        in.dataset_path = su.outputs[0].file;
        if (in.autoencoder) in.autoencoder_path = su.outputs[1].file;
        in.weights = weights_of(u);
        return in;
    }

    /// The inference weights of an eval unit's entry (f32 for the reference simulator).
    nn::WeightFormat weights_of(const Unit& u) const
    {
        return u.full_space ? nn::WeightFormat::f32
                            : m_points[u.point_index]->scenes[u.scene_index].methods[u.method_index].weights;
    }

    void run_fit(const Unit& u)
    {
        LoadedScene& ls = loaded(u.scene_unit);
        Method& method = method_of(u, ls);
        const MethodInputs in = inputs_of(u, ls, method);
        const std::string& artefact = u.outputs[0].file;
        const std::string& config_text = m_points[u.point_index]->toml_text;
        m_cache.run("integrators",
                    u.scene + ": fit '" + u.stem + "' (" + method.method_name() + ": " + method.summary() + ")", artefact,
                    u.outputs[0].key, [&] {
                        try {
                            fit_artefact(method, in, ls.scene.name, artefact, config_text);
                        } catch (const NumericalError& e) {  // name the inputs: the message knows epoch and sample
                            const Unit& su = *m_plan.find(u.scene_unit);
                            throw NumericalError("fit '" + u.stem + "' of " + u.scene + " on dataset '" +
                                                 su.outputs[0].file + "' with autoencoder '" + su.outputs[1].file +
                                                 "': " + e.what());
                        }
                    });
    }

    void run_eval(const Unit& u)
    {
        LoadedScene& ls = loaded(u.scene_unit);
        Method& method = method_of(u, ls);
        const MethodInputs in = inputs_of(u, ls, method);
        const ExperimentConfig& point = *m_points[u.point_index];
        std::vector<size_t> evaluated;
        try {
            evaluated = select_sequences(ls.data, point.sequences);
        } catch (const ConfigError& e) {
            throw ConfigError(m_ex.source + ": key 'evaluation.sequences' (" + u.scene + "): " + e.what());
        }
        const std::string& file = u.outputs[0].file;
        m_cache.run("rollouts", u.scene + ": rollout '" + u.stem + "'", file, u.outputs[0].key, [&] {
            const std::unique_ptr<Integrator> integrator = load_integrator(u, method, in, u.stem);
            RolloutOptions ro;
            ro.max_frames = point.rollout_frames;
            std::vector<RolloutResult> rolls;
            for (size_t k : evaluated) rolls.push_back(rollout(*integrator, *ls.model, ls.data.sequences[k], ro));
            save_rollouts(rolls, file, point.toml_text);
            const std::string line = method.after_rollout(*integrator);
            if (!line.empty()) log_info("%s: %s: %s", u.scene.c_str(), u.method.c_str(), line.c_str());
        });
    }

    /// An eval unit's integrator: its method loaded from the fit unit's artefact, or
    /// built directly if it has nothing to fit.
    std::unique_ptr<Integrator> load_integrator(const Unit& u, Method& method, const MethodInputs& in,
                                                const std::string& label) const
    {
        if (u.fit_unit.empty()) return method.load(in, nullptr, label);
        const h5::File f = h5::File::open(m_plan.find(u.fit_unit)->outputs[0].file);
        return method.load(in, &f, label);
    }

    /// A table row from its eval units' files: one summary per sequence and seed, and
    /// with seeds the per-seed statistics and budgets (the figures use the first seed).
    MethodResult method_result(const PlannedRow& row)
    {
        MethodResult mr;
        for (size_t k = 0; k < row.eval_units.size(); ++k) {
            const Unit& u = *m_plan.find(row.eval_units[k]);
            if (k == 0) {
                const Method& method = method_of(u, loaded(u.scene_unit));
                mr.name = row.name;
                mr.method = method.method_name();
                mr.summary = method.summary();
                if (const nn::WeightFormat w = weights_of(u); w != nn::WeightFormat::f32)
                    mr.summary += ", " + nn::to_string(w) + " inference weights";
                mr.layers = method.layers();
                mr.fit_version = method.fit_version();
                mr.paper_method = method.is_paper_method();
                mr.rollout_file = u.outputs[0].file;
                mr.rollout_key = u.outputs[0].key;
                mr.point = row.point_text;
                if (!u.fit_unit.empty()) {
                    const Unit& fit = *m_plan.find(u.fit_unit);
                    mr.embeddings = load_embedding_metrics(h5::File::open(fit.outputs[0].file));
                    if (fit.method != u.method) mr.fit_of = fit.method;
                }
            }
            std::vector<RolloutSummary> summaries;
            for (const RolloutRecord& rec : load_rollout_summaries(u.outputs[0].file)) {
                summaries.push_back(rec.summary);
                mr.sequences.push_back(rec.sequence);
                mr.summary_seeds.push_back(row.seeds.empty() ? -1 : static_cast<long long>(row.seeds[k]));
            }
            mr.summaries.insert(mr.summaries.end(), summaries.begin(), summaries.end());
            mr.budgets.push_back(u.fit_unit.empty() ? TrainingBudget{}
                                                    : read_budget(m_plan.find(u.fit_unit)->outputs[0].file));
            mr.curves.push_back(u.fit_unit.empty() ? nn::TrainingCurves{}
                                                   : nn::load_training_curves(
                                                         h5::File::open(m_plan.find(u.fit_unit)->outputs[0].file), ""));
            if (!row.seeds.empty()) {
                mr.seeds.push_back(row.seeds[k]);
                mr.per_seed.push_back(aggregate(summaries));
            }
        }
        return mr;
    }

    const ExperimentConfig& m_ex;
    std::vector<const ExperimentConfig*> m_points;
    const ExperimentPlan& m_plan;
    StageCache& m_cache;
    std::map<std::string, LoadedScene> m_loaded;
    std::unique_ptr<Method> m_reference;
};

/// Why a unit has not completed, from its status file.
std::string unit_problem(const ExperimentPlan& plan, const Unit& u)
{
    const std::string log = " (log: " + plan.run_dir + "/units/" + u.id + ".log)";
    for (const char* attempted : kStatuses) {
        const std::string marked = unwritten_path(plan.run_dir, u.id, attempted);
        const std::optional<UnitStatusRecord> kept = read_status_file(marked);
        if (!kept) continue;
        return "its last status write failed (a full disk?): the unit, started on " + kept->where +
               ", could not record '" + attempted + "'" +
               (std::string(attempted) == "failed" ? " and why" : "") + " (status '" + kept->status + "' kept as " +
               marked + "); its outputs are incomplete" + log;
    }
    const std::optional<UnitStatusRecord> record = read_unit_status(plan.run_dir, u.id);
    if (!record) return "not run";
    const std::string& status = record->status;
    const std::string& where = record->where;
    const std::string& detail = record->detail;
    if (status == "failed") return "failed on " + where + ": " + detail + log;
    if (status == "stopped") return "stopped on " + where + " at a safe point (" + detail + "); run the suite again to resume it" + log;
    if (status == "running")
        return "started on " + where + " and did not finish (killed, pre-empted or still running)" + log;
    return "ran (" + where + "), but its outputs are missing or were made with another configuration" + log;
}

/// Every table, figure and video of the suite from its units' outputs.
void merge_outputs(const ExperimentConfig& ex, const ExperimentPlan& plan, UnitRunner& runner, StageCache& cache,
                   RunResult& result)
{
    std::vector<std::string> problems;
    result.failed_units.clear();
    std::map<std::string, std::string> failed;  // contained failures: their rows are left out
    for (const Unit& u : plan.units) {
        if (unit_complete(u)) continue;
        const std::string why = unit_problem(plan, u);
        if (why.rfind("failed on ", 0) == 0 && runner.contained(u)) {
            // The tables name the log relative to the run directory (no absolute paths).
            const size_t log_at = why.rfind(" (log: ");
            failed[u.id] = why.substr(0, log_at) + " (log: units/" + u.id + ".log)";
            result.failed_units.push_back(u.id + ": " + why);
        }
        else problems.push_back("  " + u.id + ": " + why);
    }
    if (!problems.empty()) {
        std::string message = std::to_string(problems.size()) + " of " + std::to_string(plan.units.size()) +
                              " work units of " + ex.source + " have not completed, so nothing was merged:\n";
        for (const std::string& p : problems) message += p + "\n";
        message += "run each with `latentbench run " + ex.source + " -o " + plan.run_dir +
                   " --unit ID` (or submit again), then merge again";
        throw Error(message);
    }
    std::vector<SceneResult> scenes;
    for (size_t s = 0; s < ex.scenes.size(); ++s) scenes.push_back(runner.scene_result(s, failed));

    result.tables = write_tables(ex, scenes, result.run_dir + "/tables");
    write_provenance(ex, scenes, result.run_dir);
    log_info("[tables] %zu tables in %s/tables", result.tables.size(), result.run_dir.c_str());
    if (ex.diagnose) {
        for (size_t s = 0; s < ex.scenes.size(); ++s) {
            for (const std::string& p : runner.diagnose_scene(s, result.run_dir + "/tables", failed)) result.tables.push_back(p);
        }
    }
    if (ex.plots) {
        PlotOptions po;
        po.figures_dir = result.run_dir + "/figures";
        po.log_path = result.run_dir + "/run.log";
        po.filmstrips = ex.filmstrips;
        for (const SceneResult& r : scenes) {
            const std::vector<std::string> f = plot_scene(r, po);
            result.figures.insert(result.figures.end(), f.begin(), f.end());
            const std::vector<std::string> t = plot_training_curves(
                {result.run_dir + "/tables/training_" + r.label + ".csv", po.figures_dir + "/" + r.label, r.label,
                 po.log_path});
            result.figures.insert(result.figures.end(), t.begin(), t.end());
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
    // One web page of everything above, read back from the files just written.
    log_info("[page] %s", write_suite_page(result.run_dir).c_str());
}

/// After the tables are written: exit 1 naming every failed unit of a method with contained
/// failures (their rows are left out of the tables, each named in a note).
void throw_if_units_failed(const ExperimentConfig& ex, const RunResult& result)
{
    if (result.failed_units.empty()) return;
    std::string message = std::to_string(result.failed_units.size()) + " work unit(s) of " + ex.source +
                          " failed; the other methods finished and their tables are in " + result.run_dir +
                          "/tables (the failed rows are left out, each named in a note):\n";
    for (const std::string& f : result.failed_units) message += "  " + f + "\n";
    message.pop_back();
    throw Error(message);
}

/// What every entry point does first: the run directory, its log, the plan.
/// The stage that makes output `index` of `u` (for --force): a scene unit's dataset, then
/// its autoencoder; a fit's artefact; an eval's rollouts.
const char* stage_of_output(const Unit& u, size_t index)
{
    switch (u.kind) {
    case UnitKind::Scene: return index == 0 ? "simulate" : "autoencoder";
    case UnitKind::Fit: return "integrators";
    case UnitKind::Eval: return "rollouts";
    }
    return "";
}

/// `--reuse DIR`: copy into the plan's run directory every unit output that is not current
/// there and whose key a file under one of `dirs` carries (its `<file>.key`). Keys hash the
/// configuration and the inputs' keys (stage_cache.hpp), so an equal key is the same stage
/// output, whichever suite made it.
void reuse_outputs(const ExperimentPlan& plan, const std::vector<std::string>& dirs, const StageCache& cache)
{
    if (dirs.empty()) return;
    std::map<std::string, std::pair<std::string, std::string>> by_key;  // key -> (file, its --reuse directory); first wins
    for (const std::string& dir : dirs) {
        std::error_code ec;
        if (!fs::is_directory(dir, ec))
            throw ConfigError("--reuse '" + dir + "': not a directory (give another suite's run directory)");
        if (fs::equivalent(dir, plan.run_dir, ec)) continue;
        for (auto it = fs::recursive_directory_iterator(dir, fs::directory_options::skip_permission_denied, ec);
             it != fs::recursive_directory_iterator(); it.increment(ec)) {
            if (ec) break;
            const fs::path& p = it->path();
            if (it->is_directory() && (p.filename() == "units" || p.filename() == "slurm" || p.filename() == ".bin")) {
                it.disable_recursion_pending();
                continue;
            }
            if (p.extension() != ".key" || !it->is_regular_file()) continue;
            const fs::path file = p.parent_path() / p.stem();
            if (!fs::is_regular_file(file)) continue;
            std::ifstream in(p);
            std::string key;
            if (std::getline(in, key) && !key.empty()) by_key.emplace(key, std::make_pair(file.string(), dir));
        }
    }
    for (const Unit& u : plan.units) {
        int copied = 0;
        std::string from;
        for (size_t i = 0; i < u.outputs.size(); ++i) {
            const UnitOutput& o = u.outputs[i];
            if (unit_output_current(o) || cache.forced(stage_of_output(u, i))) continue;
            const auto hit = by_key.find(o.key);
            if (hit == by_key.end()) continue;
            fs::create_directories(fs::path(o.file).parent_path());
            copy_file_atomically(hit->second.first, o.file);
            write_text_atomically(o.file + ".key", o.key + "\n");
            ++copied;
            from = hit->second.second;
        }
        if (copied > 0)
            log_info("unit '%s': %d output%s reused from %s (same cache key)", u.id.c_str(), copied,
                     copied == 1 ? "" : "s", from.c_str());
    }
}

struct Session {
    Timer total;
    StageCache cache;
    RunResult result;
    ExperimentPlan plan;

    Session(const ExperimentConfig& ex, const RunOptions& options, const std::string& log_name) : cache(options.force)
    {
        if (ex.threads > 0) set_num_threads(ex.threads);
        result.run_dir = resolve_run_dir(ex, options.output_dir);
        fs::create_directories(result.run_dir + "/units");
        set_log_file(result.run_dir + "/" + log_name);
        plan = plan_experiment(ex, result.run_dir);
        reuse_outputs(plan, options.reuse, cache);
    }

    RunResult finish(const ExperimentConfig& ex, const std::string& what)
    {
        result.stages_run = cache.ran();
        result.stages_cached = cache.cached();
        result.seconds = total.seconds();
        log_info("%s '%s' finished in %.1f s: %d stages run, %d cached", what.c_str(), ex.name.c_str(), result.seconds,
                 result.stages_run, result.stages_cached);
        set_log_file("");
        return result;
    }
};

} // namespace

RunResult run_experiment(const ExperimentConfig& ex, const RunOptions& options)
{
    Session session(ex, options, "run.log");
    log_info("experiment '%s' -> %s (log: run.log): %zu work units", ex.name.c_str(), session.result.run_dir.c_str(),
             session.plan.units.size());
    write_text_atomically(session.result.run_dir + "/experiment.toml", ex.toml_text);
    UnitRunner runner(ex, session.plan, session.cache);
    try {
        std::set<std::string> failed;  // units of methods with contained failures (user code)
        for (const Unit& u : session.plan.units) {
            const auto dep = std::find_if(u.depends_on.begin(), u.depends_on.end(),
                                          [&](const std::string& d) { return failed.count(d) > 0; });
            if (dep != u.depends_on.end()) {
                write_status(session.result.run_dir, u.id, "failed", "not run: unit '" + *dep + "' failed");
                failed.insert(u.id);
                continue;
            }
            try {
                runner.run(u);
            } catch (const Stopped&) {
                throw;  // a signal stops the whole run, whoever's code was running
            } catch (const Error& e) {
                if (!runner.contained(u)) throw;
                log_warn("unit '%s' failed (the suite's other methods go on): %s", u.id.c_str(), e.what());
                failed.insert(u.id);
            }
        }
        merge_outputs(ex, session.plan, runner, session.cache, session.result);
    } catch (...) {
        set_log_file("");
        throw;
    }
    RunResult result = session.finish(ex, "experiment");
    throw_if_units_failed(ex, result);
    return result;
}

RunResult run_unit(const ExperimentConfig& ex, const std::string& id, const RunOptions& options)
{
    Session session(ex, options, "units/" + id + ".log");
    const Unit* u = session.plan.find(id);
    if (!u) {
        set_log_file("");
        throw ConfigError(ex.source + ": no work unit '" + id + "' (`latentbench plan " + ex.source + "` lists them)");
    }
    log_info("unit '%s' of '%s' -> %s", id.c_str(), ex.name.c_str(), session.result.run_dir.c_str());
    UnitRunner runner(ex, session.plan, session.cache);
    try {
        runner.run(*u);
    } catch (...) {
        set_log_file("");
        throw;
    }
    return session.finish(ex, "unit " + id + " of");
}

RunResult merge_units(const ExperimentConfig& ex, const RunOptions& options)
{
    Session session(ex, options, "run.log");
    log_info("merging the %zu work units of '%s' in %s", session.plan.units.size(), ex.name.c_str(),
             session.result.run_dir.c_str());
    write_text_atomically(session.result.run_dir + "/experiment.toml", ex.toml_text);
    UnitRunner runner(ex, session.plan, session.cache);
    try {
        merge_outputs(ex, session.plan, runner, session.cache, session.result);
    } catch (...) {
        set_log_file("");
        throw;
    }
    RunResult result = session.finish(ex, "merge of");
    throw_if_units_failed(ex, result);
    return result;
}

} // namespace lb
