#include "paper/paper_architectures.hpp"

#include "core/error.hpp"
#include "paper/paper_numbers.hpp"

namespace lb::nn {

namespace {

/// Boundary parameters per frame (§4.1): the rigid head of the bunny has a linear and
/// an angular velocity, every other example one velocity.
Index paper_bc_dim(const std::string& scene) { return scene == "bunny_ears" ? 6 : 3; }

PaperArchitecture make(const PaperTable2Row& row)
{
    PaperArchitecture a;
    a.name = row.scene;
    a.label = row.paper_example;
    a.full_dof = row.full_dofs;
    a.latent_dim = row.subspace_dofs;
    a.bc_dim = paper_bc_dim(row.scene);

    // Table 2 prints the decoder as its hidden widths followed by the PCA size.
    a.decoder.in_dim = a.latent_dim;
    a.decoder.hidden.assign(row.decoder_layers.begin(), row.decoder_layers.end() - 1);
    a.decoder.out_dim = a.full_dof;
    a.decoder.activation = ActivationKind::swish;
    a.decoder.batch_norm = true;
    a.decoder.residual = true;
    a.decoder.pca_dim = row.decoder_layers.back();
    a.decoder.pca_placement = PcaPlacement::output;

    a.integrator.in_dim = 2 * a.latent_dim + 3 * a.bc_dim;
    a.integrator.hidden.assign(row.integrator_layers.begin(), row.integrator_layers.end());
    a.integrator.out_dim = a.latent_dim;
    a.integrator.activation = ActivationKind::swish;

    a.paper_jvp_ms = row.jvp_ms;
    a.paper_total_ms = row.ours_ms;
    return a;
}

} // namespace

std::vector<PaperArchitecture> table2_architectures()
{
    std::vector<PaperArchitecture> out;
    for (const PaperTable2Row& row : paper_table2_rows()) out.push_back(make(row));
    return out;
}

PaperArchitecture table2_architecture(const std::string& name)
{
    if (const PaperTable2Row* row = find_paper_table2_row(name)) return make(*row);
    throw ConfigError("unknown Table 2 architecture '" + name +
                      "' (expected rods_rotate, rods_translate, cloth, armadillo or bunny_ears)");
}

} // namespace lb::nn
