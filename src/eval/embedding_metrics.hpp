#pragma once
// Tan et al.'s three embedding metrics (Tan, Pan, Gao & Manocha, §VI-B, Table I) for an
// autoencoder, measured with this harness's metric definitions (eval/metrics.hpp) on the
// reconstructions x̂_m = D(E(x_m)) of every ground-truth frame of a dataset:
//   M_rms   RMS vertex error of x̂_m against x_m (m)                      (summary m_rms)
//   M_STED  STED (1-ring) of the reconstructed sequence against the truth (summary sted)
//   M_phys  the physics residual of x̂_m given x̂_{m−1}, x̂_{m−2}: per-DOF RMS of the
//           implicit-Euler gradient on free DOFs over m̄|g|                (summary mean_residual)
// i.e. the metrics of a "rollout" that re-encodes the truth every frame. Frames m ≥ 2
// count; the training window (m < train_frames) and the test window apart; several
// sequences combine as in the tables (mean over sequences).
//
// Stored with a method's artefact as root attributes embedding.count = n and, for
// i < n, embedding.<i>.label and embedding.<i>.<train|test>_<m_rms|sted|m_phys>.
#include <string>
#include <vector>

#include "latent/autoencoder.hpp"
#include "sim/physics_model.hpp"

namespace lb {

namespace h5 {
class File;
}

struct EmbeddingWindow {
    double m_rms = 0.0;   ///< m
    double sted = 0.0;    ///< dimensionless
    double m_phys = 0.0;  ///< in units of m̄|g|
    int frames = 0;       ///< frames measured (summed over sequences)
};

struct EmbeddingMetrics {
    std::string label;  ///< which embedding, e.g. "shared autoencoder"
    EmbeddingWindow train, test;
};

/// The metrics of `ae` on every sequence of `data` (eval mode).
EmbeddingMetrics embedding_metrics(Autoencoder& ae, const PhysicsModel& model, const Dataset& data,
                                   const std::string& label);

void save_embedding_metrics(h5::File& file, const std::vector<EmbeddingMetrics>& rows);
/// Empty if the file has none; IoError naming the file if they are incomplete.
std::vector<EmbeddingMetrics> load_embedding_metrics(const h5::File& file);

} // namespace lb
