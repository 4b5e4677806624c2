#pragma once
// The network sizes of Li et al. 2025, Table 2 (and the DOF / latent sizes of
// Table 1), as MlpSpecs, for benchmarks and for regenerating Table 2. Derived from
// the quoted rows in paper/paper_numbers.hpp; keyed by our scene names.
//
// Decoder (paper §3.2, DESIGN §4): latent → residual blocks with BatchNorm and Swish
// at the listed hidden widths → Linear to d_pca = 50 → PCA Linear 50 → DOF (no
// activation), i.e. MlpSpec{residual, batch_norm, pca_placement = output}.
// Integrator (§3.3): MLP with Swish, no BatchNorm, input
//   [z_{t−1}, z_{t−2}, p_t, p_{t−1}, p_{t−2}]  of size 2·latent + 3·p_dim,
// with p_dim = 3 (handle velocity or angular velocity) except bunny ears, p_dim = 6
// (the rigid head's linear and angular velocity).
#include <string>
#include <vector>

#include "nn/mlp_spec.hpp"

namespace lb::nn {

struct PaperArchitecture {
    std::string name;            ///< our scene name, e.g. "armadillo", "rods_rotate"
    std::string label;           ///< e.g. "Armadillo" (as printed in the paper)
    Index full_dof = 0;
    Index latent_dim = 0;
    Index bc_dim = 0;            ///< p_dim, boundary-condition parameters per step
    MlpSpec decoder;
    MlpSpec integrator;
    double paper_jvp_ms = 0.0;   ///< Table 2 "Computing Jvp"
    double paper_total_ms = 0.0; ///< Table 2 "Ours" (integrate + decode)
};

/// The five examples of Table 2, in the paper's order.
std::vector<PaperArchitecture> table2_architectures();

/// Lookup by our scene name ("rods_rotate", "rods_translate", "cloth", "armadillo",
/// "bunny_ears"); throws ConfigError for an unknown name.
PaperArchitecture table2_architecture(const std::string& name);

} // namespace lb::nn
