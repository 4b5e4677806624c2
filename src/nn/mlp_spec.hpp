#pragma once
// Declarative MLP description and its builder, so the autoencoder and the
// integrators construct networks from configuration.
//
// make_mlp(spec) builds, in order:
//   [pca_placement == input]   Linear(in → pca_dim)                     (encoder's PCA layer, no activation)
//   for each width h in hidden:
//     residual:   ResidualBlock(prev → h)   (Linear→[BN]→act→Linear→[BN], + skip; see residual_block.hpp)
//     otherwise:  Linear(prev → h) → [BatchNorm1d(h)] → act
//   [pca_placement == output]  Linear(prev → pca_dim) → Linear(pca_dim → out)  (decoder's PCA layer, no activation)
//   otherwise                  Linear(prev → out)
//   [output_activation]        act
// The two outer PCA linears have no activation between them and the network, as in
// Fulton et al. 2019: the inner MLP works in PCA coordinates, which are unbounded.
//
// Paper (§3.2, Table 2) decoder "200, 200, 200, 50" for latent 12, 10,020 DOF:
//   {in 12, hidden {200,200,200}, out 10020, pca_dim 50, placement output,
//    batch_norm, residual, swish}; integrator "256 ×5": {in 2·12+3·p, hidden {256×5},
//    out 12, swish, no BatchNorm, no residual}.
#include <string>
#include <vector>

#include "core/rng.hpp"
#include "nn/activation.hpp"
#include "nn/sequential.hpp"

namespace lb::nn {

enum class PcaPlacement { none, input, output };

struct MlpSpec {
    Index in_dim = 0;
    std::vector<Index> hidden;                 ///< hidden widths, in order
    Index out_dim = 0;
    ActivationKind activation = ActivationKind::swish;
    bool batch_norm = false;
    bool residual = false;
    Index pca_dim = 0;                         ///< width of the PCA layer (0: none)
    PcaPlacement pca_placement = PcaPlacement::none;
    bool output_activation = false;            ///< activation after the last layer

    /// Throws ConfigError with a message naming the offending field.
    void validate() const;
    /// One line, e.g. "12 -> res[200,200,200] (bn, swish) -> 50 -> 10020".
    std::string summary() const;
};

/// Build the network described by `spec`, PyTorch-default initialised from `rng`.
Sequential make_mlp(const MlpSpec& spec, Rng& rng);

} // namespace lb::nn
