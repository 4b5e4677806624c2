#include "pipeline/deviations.hpp"

#include <cmath>
#include <map>

#include "io/toml_config.hpp"
#include "paper/paper_numbers.hpp"
#include "paper/paper_recipe.hpp"

namespace lb {

namespace {

toml::table parse_value(const std::string& text) { return toml::parse("v = " + text); }

double number_of(const toml::node& n) { return n.is_integer() ? double(n.as_integer()->get()) : n.as_floating_point()->get(); }

bool same_value(const toml::node& a, const toml::node& b)
{
    if (a.is_number() && b.is_number()) {
        const double x = number_of(a), y = number_of(b);
        return x == y || std::abs(x - y) <= 1e-12 * std::max(std::abs(x), std::abs(y));
    }
    if (a.is_array() && b.is_array()) {
        const toml::array &x = *a.as_array(), &y = *b.as_array();
        if (x.size() != y.size()) return false;
        for (size_t i = 0; i < x.size(); ++i)
            if (!same_value(*x.get(i), *y.get(i))) return false;
        return true;
    }
    return toml_value_text(a) == toml_value_text(b);
}

toml::array widths(const std::vector<Index>& w)
{
    toml::array out;
    for (Index x : w) out.push_back((long long)x);
    return out;
}

/// The autoencoder's settings under their suite keys.
toml::table autoencoder_values(const AutoencoderOptions& o)
{
    toml::table t;
    t.insert("latent", (long long)o.latent_dim);
    t.insert("hidden", widths(o.hidden));
    t.insert("pca", (long long)o.pca_dim);
    t.insert("batch_norm", o.batch_norm);
    t.insert("residual", o.residual);
    t.insert("frame", std::string(encoding_frame_name(o.frame)));
    t.insert("epochs", (long long)o.epochs);
    t.insert("batch", (long long)o.batch_size);
    t.insert("learning_rate", o.learning_rate);
    // Early stopping that cannot trigger within the budget is none.
    t.insert("patience", (long long)(o.patience >= o.epochs ? 0 : o.patience));
    t.insert("physics_epochs", (long long)o.physics_epochs);
    t.insert("validation", o.validation_fraction);
    t.insert("autoencoder_frames", to_string(o.frames_seen));
    t.insert("optimizer", "adam");
    return t;
}

/// A latent_mlp entry's settings: its resolved options text, with the keys that text leaves
/// out when they hold their defaults (so that the cache keys of older fits stay) filled in.
toml::table integrator_values(const Method& method)
{
    toml::table t = toml::parse(method.options_text());
    const std::map<std::string, toml::table> absent{
        {"noise_draw", parse_value("\"independent\"")},     {"balancing_velocity", parse_value("\"mean_velocity\"")},
        {"overwrite_dirichlet", parse_value("false")},     {"float32_decoder", parse_value("false")},
        {"boundary_input", parse_value("\"velocity\"")},  {"optimizer", parse_value("\"adam\"")}};
    for (const auto& [key, value] : absent) {
        if (!t.contains(key)) value.get("v")->visit([&](const auto& v) { t.insert(key, v); });
    }
    return t;
}

/// A value as a table shows it: strings without TOML's quotes.
std::string shown(const toml::node& value)
{
    if (const auto* text = value.as_string()) return text->get();
    if (const auto* list = value.as_array()) {
        std::string out = "[";
        for (size_t i = 0; i < list->size(); ++i) out += (i ? ", " : "") + shown(*list->get(i));
        return out + "]";
    }
    return toml_value_text(value);
}

void add_rows(Table& table, const std::string& part, const std::string& section, const std::string& loss,
              const toml::table& values, const std::vector<RecipeSetting>& recipe)
{
    for (const RecipeSetting& s : recipe) {
        if (s.section != section) continue;
        if (!s.loss.empty() && s.loss != loss) continue;
        const toml::node* value = values.get(s.key);
        if (!value) continue;  // not a setting of this part (e.g. balancing of the supervised loss)
        const std::string suite = shown(*value);
        if (!s.stated()) {
            table.add_row({part, s.key, "—", suite, "not stated",
                           s.source + "; latentbench's default " + shown(*parse_value(s.chosen).get("v"))});
            continue;
        }
        const toml::table paper = parse_value(s.paper);
        if (same_value(*paper.get("v"), *value)) continue;
        table.add_row({part, s.key, shown(*paper.get("v")), suite, "deviates", s.source});
    }
}

} // namespace

Table deviations_table(const ExperimentConfig& ex, const SceneSpec& spec, const std::string& scene_name,
                       const AutoencoderOptions& autoencoder)
{
    const std::vector<RecipeSetting> recipe = paper_recipe(scene_name);
    Table t;
    t.title = "Deviations from the paper's recipe (" + spec.label + ")";
    t.caption = "Every setting of this suite's autoencoder and latent integrators on " + spec.label + " (scene " +
                scene_name + ") that differs from what Li et al. 2025 state ('deviates': the paper's value, the "
                "suite's and the quote), and every setting the paper leaves open ('not stated': the suite's value "
                "and latentbench's default). Settings that equal the paper's are not listed. Suite recipe: " +
                (ex.recipe == "paper" ? std::string("\"paper\" (the paper's values wherever the suite sets none)")
                                      : std::string("\"none\" (latentbench's defaults)")) + ".";
    t.columns = {"part", "key", "paper", "suite", "status", "source"};
    add_rows(t, "autoencoder", "autoencoder", "", autoencoder_values(autoencoder), recipe);
    for (const MethodSpec& m : spec.methods) {
        if (m.method->method_name() != "latent_mlp") continue;  // baselines: not the paper's training
        m.method->resolve({scene_name, autoencoder.latent_dim});
        const toml::table values = integrator_values(*m.method);
        const std::string loss = values["loss"].value_or(std::string("self_supervised"));
        add_rows(t, "integrator " + m.name + " (" + loss + ")", "training", loss, values, recipe);
    }
    const int deviating = count_deviations(t);
    t.add_note(std::to_string(deviating) + (deviating == 1 ? " setting deviates" : " settings deviate") +
               " from the paper's stated recipe; source: " + std::string(kPaperCitation));
    t.add_note("the autoencoder's pca is the requested width: training clamps it to the training frames' "
               "numerical rank (logged when it does)");
    return t;
}

int count_deviations(const Table& deviations)
{
    int n = 0;
    for (const auto& row : deviations.rows) n += row.size() > 4 && row[4].text == "deviates";
    return n;
}

} // namespace lb
