#pragma once
// Rollout protocol (DESIGN §6): start from the first two ground-truth frames of
// a sequence, step autoregressively under its boundary trajectory, decode every
// frame, and measure every metric per frame. A state that turns non-finite ends
// the rollout (the remaining frames are NaN in the table).
#include <string>

#include "eval/metrics.hpp"
#include "integrators/integrator.hpp"
#include "sim/dataset.hpp"

namespace lb {

struct RolloutOptions {
    int max_frames = 0;  ///< 0: the whole sequence
    bool keep_positions = true;
    bool progress = false;
};

struct RolloutResult {
    std::string method;
    std::string sequence;
    MatrixXd positions;  ///< T × 3N (if kept)
    MatrixXd metrics;    ///< T × kNumMetricColumns
    RolloutSummary summary;
};

RolloutResult rollout(Integrator& integrator, const PhysicsModel& model, const SequenceData& sequence,
                      const RolloutOptions& options = {});

/// Boundary state of frame t of a sequence.
BoundaryState boundary_state(const SequenceData& sequence, Index t);

/// Indices of the sequences to evaluate: "test" (frames beyond their training prefix),
/// "all", or a sequence name. ConfigError if none matches.
std::vector<size_t> select_sequences(const Dataset& data, const std::string& which);

/// Method, sequence and summary of every rollout in a file written by save_rollouts.
struct RolloutRecord {
    std::string method;
    std::string sequence;
    RolloutSummary summary;
};
std::vector<RolloutRecord> load_rollout_summaries(const std::string& path);

/// Write rollouts (per-frame metrics, summaries, optionally positions) to HDF5,
/// atomically; `config_text` (what produced them) is embedded.
void save_rollouts(const std::vector<RolloutResult>& results, const std::string& path, const std::string& config_text);

} // namespace lb
