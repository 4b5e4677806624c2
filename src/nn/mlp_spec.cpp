#include "nn/mlp_spec.hpp"

#include <sstream>

#include "core/error.hpp"
#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/residual_block.hpp"

namespace lb::nn {

void MlpSpec::validate() const
{
    if (in_dim <= 0) throw ConfigError("MlpSpec.in_dim must be positive (got " + std::to_string(in_dim) + ")");
    if (out_dim <= 0) throw ConfigError("MlpSpec.out_dim must be positive (got " + std::to_string(out_dim) + ")");
    for (Index h : hidden)
        if (h <= 0) throw ConfigError("MlpSpec.hidden widths must be positive (got " + std::to_string(h) + ")");
    if (pca_placement != PcaPlacement::none && pca_dim <= 0)
        throw ConfigError("MlpSpec.pca_dim must be positive when a PCA layer is requested");
}

std::string MlpSpec::summary() const
{
    std::ostringstream os;
    os << in_dim;
    if (pca_placement == PcaPlacement::input) os << " -> pca " << pca_dim;
    if (!hidden.empty()) {
        os << " -> " << (residual ? "res[" : "[");
        for (std::size_t i = 0; i < hidden.size(); ++i) os << (i ? "," : "") << hidden[i];
        os << "] (" << (batch_norm ? "bn, " : "") << to_string(activation) << ")";
    }
    if (pca_placement == PcaPlacement::output) os << " -> " << pca_dim << " -> pca";
    os << " -> " << out_dim;
    if (output_activation) os << " (" << to_string(activation) << ")";
    return os.str();
}

Sequential make_mlp(const MlpSpec& spec, Rng& rng)
{
    spec.validate();
    Sequential net;
    Index prev = spec.in_dim;
    if (spec.pca_placement == PcaPlacement::input) {
        net.emplace<Linear>(prev, spec.pca_dim, rng);
        prev = spec.pca_dim;
    }
    for (Index h : spec.hidden) {
        if (spec.residual) {
            net.emplace<ResidualBlock>(prev, h, spec.batch_norm, spec.activation, rng);
        } else {
            net.emplace<Linear>(prev, h, rng);
            if (spec.batch_norm) net.emplace<BatchNorm1d>(h);
            net.emplace<Activation>(spec.activation);
        }
        prev = h;
    }
    if (spec.pca_placement == PcaPlacement::output) {
        net.emplace<Linear>(prev, spec.pca_dim, rng);
        net.emplace<Linear>(spec.pca_dim, spec.out_dim, rng);
    } else {
        net.emplace<Linear>(prev, spec.out_dim, rng);
    }
    if (spec.output_activation) net.emplace<Activation>(spec.activation);
    return net;
}

} // namespace lb::nn
