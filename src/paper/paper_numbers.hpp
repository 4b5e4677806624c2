#pragma once
// Published numbers of Li et al. 2025, "Self-supervised Learning of Latent
// Space Dynamics", Proc. ACM Comput. Graph. Interact. Tech. 8(4), Article 57,
// https://doi.org/10.1145/3747854 — Table 1 (comparison against the reference
// offline simulation) and Table 2 (comparison against one decoder JVP), quoted
// as printed, keyed by our scene names. Nothing here is measured or derived.
//
// Paper example -> our scene: Hair Rotation -> rods_rotate, Hair Translation ->
// rods_translate, Cloth -> cloth, Armadillo -> armadillo, Bunny Ears ->
// bunny_ears. The cantilever (Fig. 10) has no row in either table.
#include <string>
#include <string_view>
#include <vector>

#include "io/table.hpp"

namespace lb {

/// Sec. 4.7: the hardware all timings of Tables 1 and 2 come from (timings on CPU).
extern const char* const kPaperTimingHardware;
/// Short citation for table notes.
extern const char* const kPaperCitation;

/// One row of the paper's Table 1 (all times per frame, milliseconds).
struct PaperTable1Row {
    const char* scene;          ///< our scene name
    const char* paper_example;  ///< the paper's row label
    int full_dofs;
    int subspace_dofs;
    double simulation_ms;   ///< reference offline full-space simulation
    double integration_ms;  ///< ours: latent integrator
    double decoder_ms;      ///< ours: decoder
    double total_ms;        ///< ours: integration + decoder
};

/// One row of the paper's Table 2.
struct PaperTable2Row {
    const char* scene;
    const char* paper_example;
    int full_dofs;
    int subspace_dofs;
    std::vector<int> decoder_layers;     ///< widths as printed, e.g. {512, 512, 512, 50}
    std::vector<int> integrator_layers;  ///< widths as printed, e.g. {512, 512, 512}
    double jvp_ms;   ///< "Computing Jvp": one full-space vertex w.r.t. the latents, once
    double ours_ms;  ///< "Ours": the complete method (= Table 1 total)
};

/// Rows in the paper's order.
const std::vector<PaperTable1Row>& paper_table1_rows();
const std::vector<PaperTable2Row>& paper_table2_rows();
/// The row for one of our scene names, or nullptr (e.g. cantilever).
const PaperTable1Row* find_paper_table1_row(std::string_view scene);
const PaperTable2Row* find_paper_table2_row(std::string_view scene);

/// "512, 512, 512, 50"
std::string format_layers(const std::vector<int>& widths);

/// The paper's tables as lb::Table, formatted as printed, with the source
/// and hardware as notes (no provenance note: these are not our measurements).
Table paper_table1();
Table paper_table2();

} // namespace lb
