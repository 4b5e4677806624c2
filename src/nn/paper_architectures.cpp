#include "nn/paper_architectures.hpp"

#include "core/error.hpp"

namespace lb::nn {

namespace {

constexpr Index paper_pca_dim = 50;

PaperArchitecture make(std::string name, std::string label, Index dof, Index latent, Index bc_dim,
                       std::vector<Index> decoder_hidden, std::vector<Index> integrator_hidden, double jvp_ms,
                       double total_ms)
{
    PaperArchitecture a;
    a.name = std::move(name);
    a.label = std::move(label);
    a.full_dof = dof;
    a.latent_dim = latent;
    a.bc_dim = bc_dim;

    a.decoder.in_dim = latent;
    a.decoder.hidden = std::move(decoder_hidden);
    a.decoder.out_dim = dof;
    a.decoder.activation = ActivationKind::swish;
    a.decoder.batch_norm = true;
    a.decoder.residual = true;
    a.decoder.pca_dim = paper_pca_dim;
    a.decoder.pca_placement = PcaPlacement::output;

    a.integrator.in_dim = 2 * latent + 3 * bc_dim;
    a.integrator.hidden = std::move(integrator_hidden);
    a.integrator.out_dim = latent;
    a.integrator.activation = ActivationKind::swish;

    a.paper_jvp_ms = jvp_ms;
    a.paper_total_ms = total_ms;
    return a;
}

} // namespace

std::vector<PaperArchitecture> table2_architectures()
{
    return {
        make("hair_rotation", "Hair Rotation", 10800, 4, 3, {512, 512, 512}, {512, 512, 512}, 2.19, 0.720),
        make("hair_translation", "Hair Translation", 5400, 4, 3, {256, 256, 256}, {256, 256, 256}, 1.51, 0.558),
        make("cloth", "Cloth", 576, 4, 3, {200, 200, 200}, {32, 32}, 0.564, 0.272),
        make("armadillo", "Armadillo", 10020, 12, 3, {200, 200, 200}, {256, 256, 256, 256, 256}, 0.649, 0.489),
        make("bunny_ears", "Bunny Ears", 8046, 8, 6, {200, 200, 200}, {256, 256, 256, 256, 256}, 0.632, 0.426),
    };
}

PaperArchitecture table2_architecture(const std::string& name)
{
    for (auto& a : table2_architectures())
        if (a.name == name) return a;
    throw ConfigError("unknown Table 2 architecture '" + name +
                      "' (expected hair_rotation, hair_translation, cloth, armadillo or bunny_ears)");
}

} // namespace lb::nn
