#include "pipeline/plan.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "core/parse.hpp"
#include "eval/rollout.hpp"
#include "io/json.hpp"
#include "methods/full_space/full_space_method.hpp"
#include "paper/paper_recipe.hpp"
#include "paper/scene_defaults.hpp"
#include "scene/scene.hpp"

namespace lb {
namespace fs = std::filesystem;

const char* unit_kind_name(UnitKind kind)
{
    switch (kind) {
    case UnitKind::Scene: return "scene";
    case UnitKind::Fit: return "fit";
    case UnitKind::Eval: return "eval";
    }
    return "?";
}

AutoencoderOptions resolved_autoencoder(const SceneSpec& spec, const Scene& scene, std::optional<std::uint64_t> seed)
{
    AutoencoderOptions ao = spec.autoencoder;
    if (seed) ao.seed = *seed;
    if (!spec.latent_given) ao.latent_dim = default_latent_dim(scene.name);
    if (spec.recipe == "paper" && !spec.hidden_given) {
        const std::vector<long long> hidden = paper_autoencoder_hidden(scene.name);
        if (!hidden.empty()) ao.hidden.assign(hidden.begin(), hidden.end());
    }
    return ao;
}

std::string simulate_key(const Scene& scene) { return fnv1a64_hex("simulate|" + scene.resolved_toml); }

std::string autoencoder_stage_key(const std::string& sim_key, const AutoencoderOptions& o)
{
    // Every resolved option that changes the trained network.
    std::ostringstream s;
    s << o.latent_dim << "|" << format_list(o.hidden) << "|" << o.pca_dim << "|" << o.batch_norm << o.residual << "|"
      << o.epochs << "|" << o.batch_size << "|" << o.learning_rate << "|" << o.validation_fraction << "|" << o.patience
      << "|" << o.seed;
    // Since issue 39 the PCA layer is clamped to the training data's numerical rank: an
    // autoencoder cached before then may hold zero-variance completion columns.
    s << "|pca<=rank";
    if (o.frames_seen != AutoencoderFrames::train) s << "|frames=" << to_string(o.frames_seen);  // older keys unchanged
    if (o.frame != EncodingFrame::translation) s << "|frame=" << encoding_frame_name(o.frame);  // older keys unchanged
    if (o.physics_epochs > 0)
        s << "|physics=" << o.physics_epochs << "," << o.physics_weight << "," << o.physics_learning_rate << ","
          << o.physics_batch << "," << o.physics_penalty_weight;
    return fnv1a64_hex(sim_key + "|autoencoder|" + s.str());
}

std::string method_stage_key(const Method& method, const std::string& sim_key, const std::string& ae_key)
{
    const std::string& inputs_key = method.needs_autoencoder() ? ae_key : sim_key;
    const int version = method.fit_version();
    return fnv1a64_hex(inputs_key + "|" + method.method_name() + "|" + method.options_text() +
                       (version > 1 ? "|fit v" + std::to_string(version) : std::string()));
}

std::string rollout_stage_key(const std::string& method_key, const ExperimentConfig& ex, nn::WeightFormat weights)
{
    return fnv1a64_hex(method_key + "|rollout|" + ex.sequences + "|" + std::to_string(ex.rollout_frames) + "|format " +
                       std::to_string(kRolloutFormatVersion) +
                       (weights != nn::WeightFormat::f32 ? "|weights " + nn::to_string(weights) : std::string()));
}

std::string resolve_run_dir(const ExperimentConfig& ex, const std::string& output_dir)
{
    std::string dir = output_dir.empty() ? ex.output_dir : output_dir;
    if (fs::path(dir).is_relative()) dir = (fs::current_path() / dir).lexically_normal().string();
    return dir;
}

int ExperimentPlan::levels() const
{
    int most = -1;
    for (const Unit& u : units) most = std::max(most, u.level);
    return most + 1;
}

const Unit* ExperimentPlan::find(const std::string& id) const
{
    for (const Unit& u : units) {
        if (u.id == id) return &u;
    }
    return nullptr;
}

bool unit_output_current(const UnitOutput& output)
{
    if (!fs::exists(output.file)) return false;
    std::ifstream in(output.file + ".key");
    std::string key;
    std::getline(in, key);
    return key == output.key;
}

std::string unit_status_path(const std::string& run_dir, const std::string& id)
{
    return run_dir + "/units/" + id + ".status";
}

std::optional<UnitStatusRecord> read_status_file(const std::string& path)
{
    std::ifstream in(path);
    UnitStatusRecord r;
    if (!std::getline(in, r.status) || r.status.empty()) return std::nullopt;
    std::getline(in, r.where);
    for (std::string line; std::getline(in, line);)
        if (!line.empty()) r.detail += (r.detail.empty() ? "" : " ") + line;
    if (r.status == "failed" && r.detail.find(": stopped by SIG") != std::string::npos &&
        r.detail.find("the next run resumes") != std::string::npos)
        r.status = "stopped";
    return r;
}

std::optional<UnitStatusRecord> read_unit_status(const std::string& run_dir, const std::string& id)
{
    return read_status_file(unit_status_path(run_dir, id));
}

std::string unit_checkpoint_path(const Unit& unit)
{
    switch (unit.kind) {
    case UnitKind::Scene: return unit.scene_dir + "/ae.checkpoint.h5";
    case UnitKind::Fit: return unit.scene_dir + "/integrators/" + unit.stem + ".checkpoint.h5";
    case UnitKind::Eval: break;
    }
    return "";
}

bool unit_complete(const Unit& unit)
{
    return std::all_of(unit.outputs.begin(), unit.outputs.end(), unit_output_current);
}

namespace {

/// The scene units of one scene: one per distinct autoencoder configuration over the
/// sweep points (one unless the sweep varies [autoencoder] keys).
struct SceneGroup {
    std::string id, dir, sim_key, ae_key;
    Index latent = 0;
};

/// One fit of one method at one point: its seed and keys.
struct Slot {
    std::optional<std::uint64_t> seed;
    const SceneGroup* group = nullptr;  ///< the scene unit whose dataset and autoencoder it uses
    std::string fit_key, rollout_key;
    bool operator==(const Slot& o) const
    {
        return seed == o.seed && fit_key == o.fit_key && rollout_key == o.rollout_key;
    }
};

class Planner {
public:
    Planner(const ExperimentConfig& ex, ExperimentPlan& plan) : m_ex(ex), m_points(experiment_points(ex)), m_plan(plan)
    {
        m_plan.points = m_points.size();
    }

    void run()
    {
        std::vector<Unit> units;
        for (size_t s = 0; s < m_ex.scenes.size(); ++s) plan_scene(s);
        for (int level = 0; level < 3; ++level) {
            int index = 0;
            for (Unit& u : m_units) {
                if (u.level != level) continue;
                u.array_index = index++;
                units.push_back(u);
            }
        }
        m_plan.units = std::move(units);
    }

private:
    const Scene& scene_of(const SceneSpec& spec)
    {
        const std::string key = spec.scene_path + "\n" + spec.variant;
        auto it = m_scenes.find(key);
        if (it == m_scenes.end()) it = m_scenes.emplace(key, load_scene(spec.scene_path, {spec.variant})).first;
        return it->second;
    }

    void plan_scene(size_t s)
    {
        const std::string& label = m_ex.scenes[s].label;
        // One scene unit per distinct autoencoder: per sweep point whose [autoencoder] keys
        // differ, and with `[seeds] scope = "autoencoder"` per seed as well.
        const bool per_seed = m_ex.seed_scope == SeedScope::autoencoder;
        std::vector<SceneGroup> groups;
        std::vector<size_t> first_point;
        std::vector<std::optional<std::uint64_t>> group_seed;
        m_group_of.assign(m_points.size(), {});
        for (size_t p = 0; p < m_points.size(); ++p) {
            const SceneSpec& spec = m_points[p]->scenes[s];
            const Scene& scene = scene_of(spec);
            std::vector<std::optional<std::uint64_t>> variants{std::nullopt};
            if (per_seed && !m_points[p]->seeds.empty()) variants.assign(m_points[p]->seeds.begin(), m_points[p]->seeds.end());
            for (const std::optional<std::uint64_t>& seed : variants) {
                SceneGroup g;
                g.sim_key = simulate_key(scene);
                const AutoencoderOptions ao = resolved_autoencoder(spec, scene, seed);
                g.latent = ao.latent_dim;
                g.ae_key = autoencoder_stage_key(g.sim_key, ao);
                auto same = std::find_if(groups.begin(), groups.end(), [&](const SceneGroup& o) { return o.ae_key == g.ae_key; });
                if (same == groups.end()) {
                    groups.push_back(g);
                    first_point.push_back(p);
                    group_seed.push_back(seed);
                    same = groups.end() - 1;
                }
                m_group_of[p].emplace_back(seed, size_t(same - groups.begin()));
            }
        }
        const bool points_differ = std::any_of(m_group_of.begin(), m_group_of.end(),
                                               [&](const auto& v) { return v != m_group_of.front(); });
        for (size_t g = 0; g < groups.size(); ++g) {
            const ExperimentConfig& point = *m_points[first_point[g]];
            const std::string suffix = (points_differ ? "." + point.point_label : std::string()) +
                                       (group_seed[g] ? ".seed" + std::to_string(*group_seed[g]) : std::string());
            groups[g].id = "scene." + label + suffix;
            groups[g].dir = m_plan.run_dir + "/" + label + suffix;
            Unit u;
            u.id = groups[g].id;
            u.kind = UnitKind::Scene;
            u.scene = label;
            u.seed = group_seed[g];
            u.point = points_differ ? point.point_label : "";
            u.point_text = points_differ ? point.point_text : "";
            u.point_index = first_point[g];
            u.scene_index = s;
            u.scene_dir = groups[g].dir;
            u.scene_unit = u.id;
            u.outputs = {{u.scene_dir + "/data.h5", groups[g].sim_key}, {u.scene_dir + "/ae.h5", groups[g].ae_key}};
            m_units.push_back(std::move(u));
        }
        m_plan.scene_units.push_back(groups.front().id);

        const size_t methods = m_ex.scenes[s].methods.size();
        for (size_t m = 0; m <= methods; ++m) {
            if (m == methods && !m_ex.full_space) break;
            plan_method(s, m, m == methods, groups);
        }
    }

    Method& method_of(size_t p, size_t s, size_t m, bool full_space)
    {
        if (!full_space) return *m_points[p]->scenes[s].methods[m].method;
        if (!m_reference) m_reference = reference_method();
        return *m_reference;
    }

    /// The scene group whose autoencoder the fit with `seed` at point `p` uses.
    const SceneGroup& group_for(size_t p, std::optional<std::uint64_t> seed, const std::vector<SceneGroup>& groups) const
    {
        for (const auto& [group_seed, g] : m_group_of[p]) {
            if (!group_seed || group_seed == seed) return groups[g];
        }
        return groups[m_group_of[p].front().second];
    }

    std::vector<Slot> slots_of(size_t p, size_t s, size_t m, bool full_space, const std::vector<SceneGroup>& groups)
    {
        Method& method = method_of(p, s, m, full_space);
        const SceneGroup& first = groups[m_group_of[p].front().second];
        method.resolve({scene_of(m_points[p]->scenes[s]).name, first.latent});
        const std::vector<std::uint64_t>& entry_seeds =
            full_space ? m_points[p]->seeds : m_points[p]->scenes[s].methods[m].seeds;
        const std::vector<std::uint64_t>& seeds = entry_seeds.empty() ? m_points[p]->seeds : entry_seeds;
        const nn::WeightFormat weights =
            full_space ? nn::WeightFormat::f32 : m_points[p]->scenes[s].methods[m].weights;
        std::vector<Slot> slots;
        auto add = [&](std::optional<std::uint64_t> seed, const SceneGroup& g) {
            Slot slot;
            slot.seed = seed;
            slot.group = &g;
            slot.fit_key = method_stage_key(method, g.sim_key, g.ae_key);
            slot.rollout_key = rollout_stage_key(slot.fit_key, *m_points[p], weights);
            slots.push_back(slot);
        };
        // Under `[seeds] scope = "autoencoder"` a method without a seed of its own that uses
        // the autoencoder (fulton_full, say) still runs once per seed: one per autoencoder.
        const bool per_autoencoder = m_group_of[p].size() > 1 && method.needs_autoencoder();
        if (!seeds.empty() && method.set_seed(seeds.front())) {
            for (const std::uint64_t seed : seeds) {
                method.set_seed(seed);
                add(seed, group_for(p, seed, groups));
            }
        } else if (!seeds.empty() && per_autoencoder) {
            for (const std::uint64_t seed : seeds) add(seed, group_for(p, seed, groups));
        } else {
            add(std::nullopt, first);
        }
        return slots;
    }

    void plan_method(size_t s, size_t m, bool full_space, const std::vector<SceneGroup>& groups)
    {
        const std::string name = full_space ? "full_space" : m_ex.scenes[s].methods[m].name;
        std::vector<std::vector<Slot>> slots;
        for (size_t p = 0; p < m_points.size(); ++p) slots.push_back(slots_of(p, s, m, full_space, groups));
        const bool shared = std::all_of(slots.begin(), slots.end(), [&](const auto& v) { return v == slots.front(); });
        for (size_t p = 0; p < (shared ? 1 : m_points.size()); ++p) {
            PlannedRow row;
            row.scene_index = s;
            row.name = name;
            row.point_text = shared ? "" : m_points[p]->point_text;
            for (const Slot& slot : slots[p]) {
                std::string stem = name;
                if (!shared) stem += "." + m_points[p]->point_label;
                if (slot.seed) stem += ".seed" + std::to_string(*slot.seed);
                row.eval_units.push_back(unit_for(s, m, full_space, p, shared, stem, slot, *slot.group));
                if (slot.seed) row.seeds.push_back(*slot.seed);
            }
            m_plan.rows.push_back(std::move(row));
        }
    }

    /// The eval unit of one slot (and its fit unit), or the unit an earlier point
    /// planned with the same keys. Returns the eval unit's id.
    std::string unit_for(size_t s, size_t m, bool full_space, size_t p, bool shared, const std::string& stem,
                         const Slot& slot, const SceneGroup& g)
    {
        const std::string& label = m_ex.scenes[s].label;
        const std::string dedupe = g.dir + "\n" + slot.fit_key + "\n" + slot.rollout_key;
        if (auto it = m_planned.find(dedupe); it != m_planned.end()) return it->second;
        Method& method = method_of(p, s, m, full_space);
        Unit base;
        base.scene = label;
        base.method = full_space ? "full_space" : m_ex.scenes[s].methods[m].name;
        base.stem = stem;
        base.seed = slot.seed;
        base.point = shared ? "" : m_points[p]->point_label;
        base.point_text = shared ? "" : m_points[p]->point_text;
        base.point_index = p;
        base.scene_index = s;
        base.method_index = m;
        base.full_space = full_space;
        base.scene_dir = g.dir;
        base.scene_unit = g.id;
        Unit eval = base;
        eval.id = "eval." + label + "." + stem;
        eval.kind = UnitKind::Eval;
        eval.level = 1;
        eval.depends_on = {g.id};
        eval.outputs = {{g.dir + "/rollouts/" + stem + ".h5", slot.rollout_key}};
        // Another entry with the same options (one that differs only in `weights`) already
        // fits this artefact in this scene folder: roll that out rather than train it twice.
        const std::string fit_dedupe = g.dir + "\n" + slot.fit_key;
        if (auto it = m_fits.find(fit_dedupe); method.has_artefact() && it != m_fits.end()) {
            eval.level = 2;
            eval.depends_on = {it->second};
            eval.fit_unit = it->second;
        } else if (method.has_artefact()) {
            Unit fit = base;
            fit.id = "fit." + label + "." + stem;
            fit.kind = UnitKind::Fit;
            fit.level = 1;
            fit.depends_on = {g.id};
            fit.outputs = {{g.dir + "/integrators/" + stem + ".h5", slot.fit_key}};
            eval.level = 2;
            eval.depends_on = {fit.id};
            eval.fit_unit = fit.id;
            m_fits[fit_dedupe] = fit.id;
            m_units.push_back(std::move(fit));
        }
        m_planned[dedupe] = eval.id;
        m_units.push_back(eval);
        return eval.id;
    }

    const ExperimentConfig& m_ex;
    std::vector<const ExperimentConfig*> m_points;
    ExperimentPlan& m_plan;
    std::map<std::string, Scene> m_scenes;
    std::unique_ptr<Method> m_reference;
    std::vector<Unit> m_units;
    std::map<std::string, std::string> m_planned;  ///< dedupe key -> eval unit id
    std::map<std::string, std::string> m_fits;     ///< scene folder + fit key -> fit unit id
    /// Of the scene being planned, per point: (seed or none, index of its scene group).
    std::vector<std::vector<std::pair<std::optional<std::uint64_t>, size_t>>> m_group_of;
};

std::string json_strings(const std::vector<std::string>& items)
{
    std::string out = "[";
    for (size_t i = 0; i < items.size(); ++i) out += (i ? "," : "") + json_quote(items[i]);
    return out + "]";
}

} // namespace

std::unique_ptr<Method> reference_method()
{
    const toml::table empty;
    ConfigTable entry(empty, "", "full_space"), defaults(empty, "", "full_space");
    return full_space_method().parse(entry, defaults);
}

ExperimentPlan plan_experiment(const ExperimentConfig& ex, const std::string& run_dir)
{
    ExperimentPlan plan;
    plan.suite = ex.source;
    plan.run_dir = run_dir;
    Planner(ex, plan).run();
    // Names are checked to be file-name safe, but two of them can still combine into one
    // id (a method "a.p00" beside a swept method "a"): refuse rather than share files.
    std::map<std::string, int> seen;
    for (const Unit& u : plan.units) {
        if (++seen[u.id] > 1) throw ConfigError(ex.source + ": two work units would share the id '" + u.id +
                                                "' (rename an integrator or scene label)");
    }
    return plan;
}

std::string manifest_jsonl(const ExperimentConfig& ex, const ExperimentPlan& plan)
{
    const std::vector<const ExperimentConfig*> points = experiment_points(ex);
    std::ostringstream out;
    for (size_t i = 0; i < plan.units.size(); ++i) {
        const Unit& u = plan.units[i];
        out << "{\"index\":" << i << ",\"id\":" << json_quote(u.id) << ",\"kind\":\"" << unit_kind_name(u.kind)
            << "\",\"level\":" << u.level << ",\"array_index\":" << u.array_index
            << ",\"scene\":" << json_quote(u.scene)
            << ",\"method\":" << (u.method.empty() ? "null" : json_quote(u.method))
            << ",\"seed\":" << (u.seed ? std::to_string(*u.seed) : "null")
            << ",\"point\":" << (u.point.empty() ? "null" : json_quote(u.point)) << ",\"sweep\":";
        if (u.point.empty()) {
            out << "null";
        } else {
            out << "{";
            for (size_t a = 0; a < ex.sweep.size(); ++a)
                out << (a ? "," : "") << json_quote(ex.sweep[a].key) << ":"
                    << json_quote(points[u.point_index]->point_values[a]);
            out << "}";
        }
        std::vector<std::string> files;
        for (const UnitOutput& o : u.outputs) files.push_back(o.file);
        out << ",\"depends_on\":" << json_strings(u.depends_on) << ",\"outputs\":" << json_strings(files) << "}\n";
    }
    return out.str();
}

} // namespace lb
