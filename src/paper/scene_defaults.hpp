#pragma once
// Per-scene defaults taken from the paper (Li et al. 2025): the latent size of
// Table 1's "Subspace DoF" column and the integrator widths of Table 2, looked up
// by our scene name in paper/paper_numbers.hpp. Scenes the paper does not list
// (the cantilever, anything new) get the fallbacks below.
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lb {

/// Latent size when a scene's autoencoder does not set one.
constexpr Index kFallbackLatentDim = 4;
/// Integrator widths for scenes without a Table 2 row (the solids' widths).
const std::vector<Index>& fallback_integrator_hidden();

/// Table 1's subspace DOF for the scene (rods 4, cloth 4, armadillo 12, bunny_ears 8),
/// else kFallbackLatentDim.
Index default_latent_dim(const std::string& scene_name);
/// Table 2's integrator layers for the scene (cloth 32×2, rods_rotate 512×3,
/// rods_translate 256×3, solids 256×5), else fallback_integrator_hidden().
std::vector<Index> default_integrator_hidden(const std::string& scene_name);

} // namespace lb
