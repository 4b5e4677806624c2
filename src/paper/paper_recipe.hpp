#pragma once
// The paper's training recipe as data (issue 39): every autoencoder and integrator
// setting that Li et al. 2025 state, each with the sentence or table it is taken from,
// and every setting the paper leaves open, marked "not stated in the paper" with the
// value latentbench uses. Keys are the suite keys of `[autoencoder]` and `[training]`
// (README, "Experiment files"); values are TOML text ("1.0e-4" is written "0.0001").
//
// A suite that says `recipe = "paper"` gets the stated values for every key it does not
// set itself (pipeline/experiment_config.cpp); every suite's tables hold a deviations
// table (deviations_<scene>.*) listing where its resolved settings differ from these.
#include <string>
#include <vector>

namespace lb {

struct RecipeSetting {
    std::string section;  ///< "autoencoder" or "training" (the suite table the key lives in)
    std::string key;      ///< suite key, e.g. "learning_rate"
    /// The paper's value as TOML text; empty when the paper does not state one.
    std::string paper;
    /// Not stated: latentbench's default (TOML text), shown beside "not stated in the paper".
    std::string chosen;
    /// The quote (with its section or table), or why the value is open.
    std::string source;
    /// Which integrator losses the key applies to: "" every one, "self_supervised" only it.
    std::string loss;
    bool stated() const { return !paper.empty(); }
};

/// The recipe for one of our scene names: the scene-independent settings plus the widths and
/// latent sizes of Tables 1 and 2 where the paper lists the scene (the cantilever is not in
/// them: its widths are "not stated").
std::vector<RecipeSetting> paper_recipe(const std::string& scene_name);

/// The stated values that `recipe = "paper"` writes into a suite's [autoencoder] or
/// [training] table when the suite does not set them, scene-independent only (the
/// per-scene widths and latent sizes are resolved per scene from Tables 1 and 2).
std::vector<RecipeSetting> paper_recipe_suite_defaults(const std::string& section);

/// The paper's autoencoder hidden widths for a scene (Table 2's decoder layers without the
/// PCA width), or empty when the scene is not in Table 2.
std::vector<long long> paper_autoencoder_hidden(const std::string& scene_name);

} // namespace lb
