#pragma once
// Deviations from the paper's recipe (issue 39): for one scene of a suite, every resolved
// autoencoder setting and every latent_mlp entry's training setting compared with
// paper/paper_recipe.hpp. A row per key where the suite differs from a stated value
// ("deviates"), and a row per key the paper leaves open ("not stated"), each with the
// paper's value, the suite's and the quote. `run --check` prints the table; every run writes
// it as tables/deviations_<scene>.{md,csv,tex}. Nothing a suite sets can deviate silently:
// the values compared are the resolved ones the stage keys are made of.
#include <string>

#include "io/table.hpp"
#include "latent/autoencoder.hpp"
#include "pipeline/experiment.hpp"

namespace lb {

/// @param spec         one scene of the suite (its methods resolved or not: resolved here)
/// @param scene_name   the scene's name (e.g. "armadillo"), for Tables 1 and 2
/// @param autoencoder  the scene's resolved autoencoder options (resolved_autoencoder)
Table deviations_table(const ExperimentConfig& ex, const SceneSpec& spec, const std::string& scene_name,
                       const AutoencoderOptions& autoencoder);

/// Number of "deviates" rows of a deviations table.
int count_deviations(const Table& deviations);

} // namespace lb
