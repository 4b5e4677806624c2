#include "lb_paths.hpp"

#include <algorithm>
#include <cmath>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "core/error.hpp"

#include "eval/rollout.hpp"
#include "io/toml_config.hpp"
#include "latent/autoencoder_option_table.hpp"
#include "paper/paper_recipe.hpp"
#include "pipeline/experiment.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

std::string resolve(const std::string& path, const std::string& base)
{
    if (fs::path(path).is_absolute()) return path;
    if (fs::exists(fs::path(base) / path)) return (fs::path(base) / path).string();
    // A published suite's experiment.toml (results/<suite>/) names its scenes relative to
    // experiments/, where its suite file was.
    const fs::path in_experiments = fs::path(LB_SOURCE_DIR) / "experiments" / path;
    if (!fs::exists(fs::path(LB_SOURCE_DIR) / path) && fs::exists(in_experiments)) return in_experiments.string();
    return (fs::path(LB_SOURCE_DIR) / path).string();
}

/// An integer key of [autoencoder], range-checked against the option table.
long long ae_int(ConfigTable& t, const char* key, long long fallback)
{
    const AutoencoderOptionSpec& spec = autoencoder_option_by_key(key);
    return t.get_int(key, fallback, spec.int_min, spec.int_max);
}

/// A real key of [autoencoder], range-checked against the option table.
double ae_real(ConfigTable& t, const char* key, double fallback)
{
    const double value = t.get_double(key, fallback);
    if (t.has(key)) {
        const std::string problem = autoencoder_option_by_key(key).problem(value);
        if (!problem.empty()) t.fail(key, problem);
    }
    return value;
}

void read_autoencoder(ConfigTable t, AutoencoderOptions& o, bool& latent_given, bool& hidden_given)
{
    if (t.has("latent")) {
        o.latent_dim = Index(ae_int(t, "latent", 0));
        latent_given = true;
    }
    hidden_given = hidden_given || t.has("hidden");
    o.hidden = t.get_widths("hidden", o.hidden);
    o.pca_dim = Index(ae_int(t, "pca", o.pca_dim));
    o.epochs = int(ae_int(t, "epochs", o.epochs));
    o.batch_size = int(ae_int(t, "batch", o.batch_size));
    o.learning_rate = ae_real(t, "learning_rate", o.learning_rate);
    o.patience = int(ae_int(t, "patience", o.patience));
    o.validation_fraction = ae_real(t, "validation", o.validation_fraction);
    o.batch_norm = t.get_bool("batch_norm", o.batch_norm);
    o.residual = t.get_bool("residual", o.residual);
    if (t.has("frame")) {
        try {
            o.frame = parse_encoding_frame(t.get_string("frame", ""));
        } catch (const ConfigError& e) {
            t.fail("frame", e.what());
        }
    }
    if (t.has("autoencoder_frames")) {
        try {
            o.frames_seen = autoencoder_frames_from_string(t.get_string("autoencoder_frames", ""));
        } catch (const ConfigError& e) {
            t.fail("autoencoder_frames", e.what());
        }
    }
    o.seed = std::uint64_t(ae_int(t, "seed", (long long)o.seed));
    o.physics_epochs = int(ae_int(t, "physics_epochs", o.physics_epochs));
    o.physics_weight = ae_real(t, "physics_weight", o.physics_weight);
    o.physics_learning_rate = ae_real(t, "physics_learning_rate", o.physics_learning_rate);
    o.physics_batch = int(ae_int(t, "physics_batch", o.physics_batch));
    t.finish();
}

/// Names and labels become file and folder names under the run directory: letters,
/// digits, '_', '-' and '.', not starting with '.', at most 64 characters (so no
/// path separators, no "..", nothing a shell or a file system would interpret).
bool is_safe_name(const std::string& name)
{
    if (name.empty() || name.size() > 64 || name.front() == '.') return false;
    for (unsigned char c : name) {
        if (!(std::isalnum(c) || c == '_' || c == '-' || c == '.')) return false;
    }
    return true;
}

constexpr const char* kSafeNameRule = "must be 1-64 letters, digits, '_', '-' or '.', not starting with '.'";

/// The [[integrators]] entries, checked once for names (the methods parse them per scene).
std::vector<ConfigTable> method_entries(ConfigTable& cfg, std::set<std::string>& names)
{
    std::vector<ConfigTable> entries = cfg.table_array("integrators");
    if (entries.empty()) cfg.fail("integrators", "at least one [[integrators]] entry is required");
    for (ConfigTable& t : entries) {
        const std::string name = t.require_string("name");
        if (!is_safe_name(name)) t.fail("name", std::string(kSafeNameRule) + " (got '" + name + "')");
        if (name == "full_space") t.fail("name", "'full_space' is reserved for the reference simulator");
        if (!names.insert(name).second) t.fail("name", "duplicate integrator name '" + name + "'");
    }
    return entries;
}

/// One scene: its autoencoder settings and every method parsed over the merged
/// [training] defaults (suite-wide, then the scene's [scenes.training]).
SceneSpec read_scene(ConfigTable s, const std::string& base, const AutoencoderOptions& ae_defaults,
                     bool latent_default_given, bool hidden_default_given, const toml::table* training, const std::vector<ConfigTable>& entries,
                     const MethodRegistry& registry, const std::string& source,
                     const std::vector<std::uint64_t>& suite_seeds)
{
    SceneSpec sc;
    sc.scene_path = resolve(s.require_string("scene"), base);
    if (!fs::exists(sc.scene_path)) s.fail("scene", "file '" + sc.scene_path + "' does not exist");
    sc.variant = s.get_string("variant", "");
    sc.label = s.get_string("label", fs::path(sc.scene_path).stem().string() + (sc.variant.empty() ? "" : "_" + sc.variant));
    if (!is_safe_name(sc.label)) s.fail("label", std::string(kSafeNameRule) + " (got '" + sc.label + "')");
    sc.autoencoder = ae_defaults;
    sc.latent_given = latent_default_given;
    sc.hidden_given = hidden_default_given;
    if (auto t = s.table("autoencoder")) read_autoencoder(*t, sc.autoencoder, sc.latent_given, sc.hidden_given);
    toml::table merged = training ? *training : toml::table{};
    std::optional<ConfigTable> scene_training = s.table("training");
    if (scene_training) {
        scene_training->accept_all();
        merge_toml(merged, *s.raw_table("training"));
    }
    ConfigTable defaults(merged, scene_training ? "scenes.training" : "training", source);
    // `integrators = [...]`: only these entries on this scene (e.g. an autoencoder variant
    // that some methods cannot use); default every entry.
    std::set<std::string> only;
    if (s.has("integrators")) {
        std::set<std::string> known;
        for (ConfigTable entry : entries) known.insert(entry.require_string("name"));
        for (const std::string& name : s.get_string_array("integrators", {})) {
            if (!known.count(name)) s.fail("integrators", "no [[integrators]] entry is named '" + name + "'");
            only.insert(name);
        }
        if (only.empty()) s.fail("integrators", "lists no integrator (leave it out to run every one)");
    }
    for (ConfigTable entry : entries) {
        if (!only.empty() && !only.count(entry.require_string("name"))) {
            entry.accept_all();
            continue;
        }
        MethodSpec m;
        m.name = entry.require_string("name");
        if (entry.has("seeds")) {
            if (suite_seeds.empty())
                entry.fail("seeds", "an entry runs a subset of the suite's seeds; the suite sets no seeds = [...]");
            for (const long long seed : entry.get_int_array("seeds", {}, 0, kMaxSeed)) {
                if (std::find(suite_seeds.begin(), suite_seeds.end(), std::uint64_t(seed)) == suite_seeds.end())
                    entry.fail("seeds", "seed " + std::to_string(seed) + " is not one of the suite's seeds");
                if (std::find(m.seeds.begin(), m.seeds.end(), std::uint64_t(seed)) != m.seeds.end())
                    entry.fail("seeds", "duplicate seed " + std::to_string(seed));
                m.seeds.push_back(std::uint64_t(seed));
            }
            if (m.seeds.empty()) entry.fail("seeds", "list at least one seed (or leave the key out)");
        }
        const std::string weights = entry.get_string("weights", "f32");
        try {
            m.weights = nn::weight_format_from_string(weights);
        } catch (const std::invalid_argument& e) {
            entry.fail("weights", e.what());
        }
        m.method = registry.parse(entry, defaults);
        if (m.weights != nn::WeightFormat::f32 && !m.method->uses_weight_format())
            entry.fail("weights", "method '" + m.method->method_name() +
                                      "' does not roll out through the float inference network (latent_mlp and "
                                      "tan_physics_mlp do); leave the key out");
        sc.methods.push_back(std::move(m));
    }
    defaults.finish();  // a [training] key that no method reads is a typo
    s.finish();
    return sc;
}

AblationSpec read_ablation(ConfigTable a, const std::set<std::string>& names)
{
    AblationSpec ab;
    ab.name = a.require_string("name");
    if (!is_safe_name(ab.name)) a.fail("name", std::string(kSafeNameRule) + " (got '" + ab.name + "')");
    ab.title = a.get_string("title", ab.name);
    ab.methods = a.get_string_array("methods", {});
    for (const auto& m : ab.methods) {
        if (!names.count(m)) a.fail("methods", "unknown integrator '" + m + "'");
    }
    if (ab.methods.size() < 2) a.fail("methods", "an ablation compares at least two integrators");
    a.finish();
    return ab;
}

} // namespace

const char* seed_scope_name(SeedScope scope)
{
    return scope == SeedScope::autoencoder ? "autoencoder" : "integrator";
}

const std::vector<std::string>& experiment_stages()
{
    static const std::vector<std::string> stages{"simulate", "autoencoder", "integrators", "rollouts", "tables", "plots", "videos", "diagnose"};
    return stages;
}

namespace {

/// One configuration from its TOML root (a suite without [sweep], or one sweep point).
ExperimentConfig parse_experiment(const toml::table& root, const std::string& path, const MethodRegistry& registry)
{
    ConfigTable cfg(root, "", path);
    const std::string base = fs::path(path).parent_path().string();
    ExperimentConfig ex;
    ex.source = path;
    ex.toml_text = to_toml_string(root);
    ex.name = cfg.require_string("name");
    if (!is_safe_name(ex.name)) cfg.fail("name", std::string(kSafeNameRule) + " (got '" + ex.name + "')");
    ex.description = cfg.get_string("description", "");
    ex.output_dir = cfg.get_string("output_dir", "runs/" + ex.name);
    ex.threads = cfg.get_count("threads", 0, 0, kMaxThreads);
    // `seeds = [0, 1, 2]`, or a table `[seeds]` with `values = [...]` and `scope`.
    std::optional<ConfigTable> seed_table = root.contains("seeds") && root.at("seeds").is_table()
                                                ? std::optional<ConfigTable>(cfg.require_table("seeds"))
                                                : std::nullopt;
    ConfigTable& seed_cfg = seed_table ? *seed_table : cfg;
    const std::string seed_key = seed_table ? "values" : "seeds";
    if (seed_table && !seed_table->has("values")) seed_table->fail("values", "list the seeds: values = [0, 1, 2]");
    for (const long long seed : seed_cfg.get_int_array(seed_key, {}, 0, kMaxSeed)) {
        constexpr size_t kMaxSeeds = 100;
        if (std::find(ex.seeds.begin(), ex.seeds.end(), std::uint64_t(seed)) != ex.seeds.end())
            seed_cfg.fail(seed_key, "duplicate seed " + std::to_string(seed));
        ex.seeds.push_back(std::uint64_t(seed));
        if (ex.seeds.size() > kMaxSeeds) seed_cfg.fail(seed_key, "at most " + std::to_string(kMaxSeeds) + " seeds");
    }
    if (seed_cfg.has(seed_key) && ex.seeds.empty())
        seed_cfg.fail(seed_key, "list at least one seed (or leave the key out)");
    if (seed_table) {
        const std::string scope = seed_table->get_string("scope", seed_scope_name(ex.seed_scope));
        if (scope == "autoencoder")
            ex.seed_scope = SeedScope::autoencoder;
        else if (scope != "integrator")
            seed_table->fail("scope", "unknown scope '" + scope + "' (integrator: a seed varies each method's own "
                                      "initialisation over one autoencoder; autoencoder: every seed also trains "
                                      "its own autoencoder)");
        seed_table->finish();
    }

    ex.recipe = cfg.get_string("recipe", ex.recipe);
    if (ex.recipe != "paper" && ex.recipe != "none")
        cfg.fail("recipe", "unknown recipe '" + ex.recipe + "' (paper: the settings Li et al. 2025 state; none: "
                           "latentbench's defaults)");
    AutoencoderOptions ae_defaults;
    bool latent_default_given = false, hidden_default_given = false;
    if (auto t = cfg.table("autoencoder")) read_autoencoder(*t, ae_defaults, latent_default_given, hidden_default_given);
    if (auto t = cfg.table("training")) t->accept_all();  // read by the methods, checked per scene
    std::set<std::string> names;
    const std::vector<ConfigTable> entries = method_entries(cfg, names);
    for (ConfigTable s : cfg.table_array("scenes")) {
        ex.scenes.push_back(read_scene(s, base, ae_defaults, latent_default_given, hidden_default_given,
                                       cfg.raw_table("training"), entries, registry, path, ex.seeds));
        ex.scenes.back().recipe = ex.recipe;
    }
    if (ex.scenes.empty()) cfg.fail("scenes", "at least one [[scenes]] entry is required");

    if (auto t = cfg.table("evaluation")) {
        ex.sequences = t->get_string("sequences", ex.sequences);
        const long long frames = t->get_int("frames", 0, std::numeric_limits<long long>::min(),
                                            std::numeric_limits<long long>::max());  // rollout_frames_problem checks
        const std::string problem = rollout_frames_problem(frames);
        if (!problem.empty()) t->fail("frames", problem);
        ex.rollout_frames = int(frames);
        ex.full_space = t->get_bool("full_space", ex.full_space);
        t->finish();
    }
    if (auto t = cfg.table("outputs")) {
        ex.plots = t->get_bool("plots", ex.plots);
        ex.filmstrips = t->get_bool("filmstrips", ex.filmstrips);
        ex.paper_tables = t->get_bool("paper_tables", ex.paper_tables);
        ex.videos = t->get_bool("videos", ex.videos);
        ex.video_frames = t->get_count("video_frames", ex.video_frames, 2, 100000);
        ex.diagnose = t->get_bool("diagnose", ex.diagnose);
        ex.diagnose_stride = t->get_count("diagnose_stride", ex.diagnose_stride, 1, 1000000);
        t->finish();
    }
    for (ConfigTable a : cfg.table_array("ablations")) ex.ablations.push_back(read_ablation(a, names));
    cfg.finish();
    return ex;
}

/// The [sweep] axes: dotted keys (quoted, "training.noise_fraction", or as nested
/// tables, training.noise_fraction) naming `seeds`, a [training] or an [autoencoder]
/// key, each a non-empty list of distinct values.
void read_sweep_axes(const toml::table& table, const std::string& prefix, const std::string& path,
                     std::vector<SweepAxis>& axes, std::vector<const toml::array*>& values)
{
    for (const auto& [k, node] : table) {
        const std::string key = prefix + std::string(k.str());
        auto fail = [&](const std::string& message) {
            throw ConfigError(path + ": key 'sweep." + key + "': " + message);
        };
        if (const toml::table* sub = node.as_table()) {
            read_sweep_axes(*sub, key + ".", path, axes, values);
            continue;
        }
        const size_t dot = key.find('.');
        const std::string head = key.substr(0, dot);
        const bool known = key == "seeds" || ((head == "training" || head == "autoencoder") && dot != std::string::npos &&
                                              key.find('.', dot + 1) == std::string::npos && dot + 1 < key.size());
        if (!known) fail("unknown sweep key (a sweep varies 'seeds', 'training.<key>' or 'autoencoder.<key>')");
        const toml::array* list = node.as_array();
        if (!list) fail("must be a list of the values to sweep, e.g. [0.0, 0.1]");
        if (list->empty()) fail("list at least one value");
        SweepAxis axis;
        axis.key = key;
        for (const toml::node& v : *list) {
            if (key == "seeds" && !(v.is_integer() && v.as_integer()->get() >= 0))
                fail("seeds are integers >= 0 (got " + toml_value_text(v) + ")");
            const std::string text = toml_value_text(v);
            if (std::find(axis.values.begin(), axis.values.end(), text) != axis.values.end())
                fail("duplicate value " + text);
            axis.values.push_back(text);
        }
        axes.push_back(std::move(axis));
        values.push_back(list);
    }
}

/// `root` with the sweep's values at `choice` (an index per axis; -1 leaves the axis
/// at the suite's own setting) and without [sweep].
toml::table point_root(const toml::table& root, const std::vector<SweepAxis>& axes,
                       const std::vector<const toml::array*>& values, const std::vector<long>& choice)
{
    toml::table out = root;
    out.erase("sweep");
    for (size_t a = 0; a < axes.size(); ++a) {
        if (choice[a] < 0) continue;
        const toml::node& v = *values[a]->get(size_t(choice[a]));
        if (axes[a].key == "seeds") {
            toml::array seeds;
            seeds.push_back(*v.as_integer());
            out.insert_or_assign("seeds", std::move(seeds));
            continue;
        }
        const size_t dot = axes[a].key.find('.');
        const std::string table_key = axes[a].key.substr(0, dot), key = axes[a].key.substr(dot + 1);
        if (!out.contains(table_key)) out.insert(table_key, toml::table{});
        toml::table* t = out.get_as<toml::table>(table_key);
        if (!t) throw ConfigError("key '" + table_key + "' must be a table to sweep '" + axes[a].key + "'");
        v.visit([&](const auto& value) { t->insert_or_assign(key, value); });
    }
    return out;
}

std::string point_text(const std::vector<SweepAxis>& axes, const std::vector<long>& choice)
{
    std::string text;
    for (size_t a = 0; a < axes.size(); ++a) {
        if (choice[a] < 0) continue;
        text += (text.empty() ? "" : ", ") + axes[a].key + "=" + axes[a].values[size_t(choice[a])];
    }
    return text;
}

/// Parse one sweep point; an error names the sweep key (or the point) that caused it.
ExperimentConfig parse_point(const toml::table& root, const std::string& path, const MethodRegistry& registry,
                             const std::string& what)
{
    try {
        return parse_experiment(root, path, registry);
    } catch (const ConfigError& e) {
        std::string inner = e.what();
        if (inner.rfind(path + ": ", 0) == 0) inner = inner.substr(path.size() + 2);
        throw ConfigError(path + ": " + what + ": " + inner);
    }
}

/// Expand [sweep] into ex.points: each axis is checked alone first (so an error names
/// its key), then every point of the product.
void expand_sweep(const toml::table& root, const std::string& path, const MethodRegistry& registry,
                  ExperimentConfig& ex)
{
    const toml::node* node = root.get("sweep");
    if (!node) return;
    const toml::table* sweep = node->as_table();
    if (!sweep) throw ConfigError(path + ": key 'sweep': must be a table ([sweep])");
    std::vector<const toml::array*> values;
    read_sweep_axes(*sweep, "", path, ex.sweep, values);
    if (ex.sweep.empty()) throw ConfigError(path + ": key 'sweep': list at least one key to sweep");
    {
        // TOML tables iterate in key order; the axes keep the file's order (the first
        // written varies slowest).
        std::vector<size_t> order(ex.sweep.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        auto position = [&](size_t i) {
            const toml::source_position p = values[i]->source().begin;
            return std::make_pair(p.line, p.column);
        };
        std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return position(a) < position(b); });
        std::vector<SweepAxis> axes;
        std::vector<const toml::array*> lists;
        for (size_t i : order) {
            axes.push_back(ex.sweep[i]);
            lists.push_back(values[i]);
        }
        ex.sweep = std::move(axes);
        values = std::move(lists);
    }
    size_t count = 1;
    for (const SweepAxis& a : ex.sweep) {
        if (a.key == "seeds" && root.contains("seeds"))
            throw ConfigError(path + ": key 'sweep.seeds': the suite also sets 'seeds'; list them in one place");
        count *= a.values.size();
        if (count > kMaxSweepPoints)
            throw ConfigError(path + ": key 'sweep': more than " + std::to_string(kMaxSweepPoints) + " points");
    }
    for (size_t a = 0; a < ex.sweep.size(); ++a) {
        for (size_t v = 0; v < ex.sweep[a].values.size(); ++v) {
            std::vector<long> choice(ex.sweep.size(), -1);
            choice[a] = long(v);
            const std::string what = "key 'sweep." + ex.sweep[a].key + "' = " + ex.sweep[a].values[v];
            try {
                parse_point(point_root(root, ex.sweep, values, choice), path, registry, what);
            } catch (const ConfigError& e) {
                if (std::string(e.what()).rfind(path + ": ", 0) == 0) throw;
                throw ConfigError(path + ": " + what + ": " + e.what());
            }
        }
    }
    const int digits = count > 100 ? 3 : 2;
    for (size_t i = 0; i < count; ++i) {
        std::vector<long> choice(ex.sweep.size());
        size_t rest = i;
        for (size_t a = ex.sweep.size(); a-- > 0;) {
            choice[a] = long(rest % ex.sweep[a].values.size());
            rest /= ex.sweep[a].values.size();
        }
        const std::string text = point_text(ex.sweep, choice);
        const toml::table proot = point_root(root, ex.sweep, values, choice);
        ExperimentConfig point = parse_point(proot, path, registry, "[sweep] point " + text);
        char label[16];
        std::snprintf(label, sizeof label, "p%0*zu", digits, i);
        point.point_label = label;
        point.point_text = text;
        for (size_t a = 0; a < ex.sweep.size(); ++a) point.point_values.push_back(ex.sweep[a].values[size_t(choice[a])]);
        point.toml_text = "# sweep point " + point.point_label + ": " + text + "\n" + to_toml_string(proot);
        ex.points.push_back(std::move(point));
    }
}

/// `recipe = "paper": the paper's stated [autoencoder] and [training] values for every key
/// the suite does not set (the per-scene widths and latent sizes resolve per scene).
toml::table with_recipe(toml::table root, const std::string& path)
{
    const toml::node* recipe = root.get("recipe");
    if (!recipe || recipe->value_or(std::string()) != "paper") return root;  // parse_experiment checks the value
    for (const char* section : {"autoencoder", "training"}) {
        if (!root.contains(section)) root.insert(section, toml::table{});
        toml::table* t = root.get_as<toml::table>(section);
        if (!t) throw ConfigError(path + ": key '" + section + "': must be a table");
        for (const RecipeSetting& s : paper_recipe_suite_defaults(section)) {
            if (t->contains(s.key)) continue;
            toml::table parsed = toml::parse("v = " + s.paper);
            parsed.get("v")->visit([&](const auto& value) { t->insert(s.key, value); });
        }
    }
    return root;
}

} // namespace

ExperimentConfig load_experiment(const std::string& path, const MethodRegistry& registry)
{
    const toml::table root = with_recipe(parse_toml_file(path), path);
    toml::table base = root;
    base.erase("sweep");
    ExperimentConfig ex = parse_experiment(base, path, registry);
    ex.toml_text = to_toml_string(root);
    expand_sweep(root, path, registry, ex);
    return ex;
}

namespace {

/// select_subset on one configuration (a suite or a sweep point); `note` is the comment line.
void keep_subset(ExperimentConfig& ex, const std::set<std::string>& scenes, const std::set<std::string>& integrators,
                 const std::string& note)
{
    std::vector<SceneSpec> kept;
    for (SceneSpec& s : ex.scenes) {
        if (!scenes.empty() && !scenes.count(s.label)) continue;
        if (!integrators.empty()) {
            std::vector<MethodSpec> methods;
            for (MethodSpec& m : s.methods)
                if (integrators.count(m.name)) methods.push_back(std::move(m));
            if (methods.empty())
                throw ConfigError(ex.source + ": scene '" + s.label + "' runs none of the selected integrators");
            s.methods = std::move(methods);
        }
        kept.push_back(std::move(s));
    }
    ex.scenes = std::move(kept);
    std::vector<AblationSpec> ablations;
    for (AblationSpec& a : ex.ablations) {
        const bool whole = integrators.empty() || std::all_of(a.methods.begin(), a.methods.end(), [&](const std::string& m) {
                               return integrators.count(m) > 0;
                           });
        if (whole) ablations.push_back(std::move(a));
    }
    ex.ablations = std::move(ablations);
    ex.toml_text = note + ex.toml_text;
}

} // namespace

ExperimentConfig select_subset(const ExperimentConfig& ex, const std::vector<std::string>& scenes,
                               const std::vector<std::string>& integrators)
{
    std::set<std::string> labels, names;
    for (const SceneSpec& s : ex.scenes) {
        labels.insert(s.label);
        for (const MethodSpec& m : s.methods) names.insert(m.name);
    }
    auto join_set = [](const std::set<std::string>& v) {
        std::string out;
        for (const std::string& x : v) out += (out.empty() ? "" : ", ") + x;
        return out;
    };
    for (const std::string& s : scenes)
        if (!labels.count(s))
            throw ConfigError(ex.source + ": no scene is labelled '" + s + "' (labels: " + join_set(labels) + ")");
    for (const std::string& m : integrators)
        if (!names.count(m))
            throw ConfigError(ex.source + ": no [[integrators]] entry is named '" + m + "' (names: " + join_set(names) +
                              ")");
    const std::set<std::string> scene_set(scenes.begin(), scenes.end()), method_set(integrators.begin(), integrators.end());
    std::string note = "# subset run:";
    if (!scenes.empty()) note += " scenes " + join_set(scene_set) + ";";
    if (!integrators.empty()) note += " integrators " + join_set(method_set) + ";";
    note += "\n";
    ExperimentConfig out = ex;
    keep_subset(out, scene_set, method_set, note);
    for (ExperimentConfig& point : out.points) keep_subset(point, scene_set, method_set, note);
    if (out.scenes.empty()) throw ConfigError(ex.source + ": the subset keeps no scene");
    return out;
}

std::vector<const ExperimentConfig*> experiment_points(const ExperimentConfig& ex)
{
    std::vector<const ExperimentConfig*> out;
    for (const ExperimentConfig& p : ex.points) out.push_back(&p);
    if (out.empty()) out.push_back(&ex);
    return out;
}

} // namespace lb
