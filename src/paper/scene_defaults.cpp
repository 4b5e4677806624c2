#include "paper/scene_defaults.hpp"

#include "paper/paper_numbers.hpp"

namespace lb {

const std::vector<Index>& fallback_integrator_hidden()
{
    static const std::vector<Index> widths{256, 256, 256, 256, 256};
    return widths;
}

Index default_latent_dim(const std::string& scene_name)
{
    const PaperTable1Row* row = find_paper_table1_row(scene_name);
    return row ? Index(row->subspace_dofs) : kFallbackLatentDim;
}

std::vector<Index> default_integrator_hidden(const std::string& scene_name)
{
    const PaperTable2Row* row = find_paper_table2_row(scene_name);
    if (!row) return fallback_integrator_hidden();
    return std::vector<Index>(row->integrator_layers.begin(), row->integrator_layers.end());
}

} // namespace lb
