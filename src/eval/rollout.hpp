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

/// Shortest rollout: the two initial ground-truth frames and one step.
inline constexpr long long kMinRolloutFrames = 3;
/// Longest frame limit accepted from a config or the command line (10^7 frames,
/// 3.9 days of simulated time at 30 fps); checked before any int conversion.
inline constexpr long long kMaxRolloutFrames = 10'000'000;

/// "" if `frames` is a valid rollout length limit (0: the whole sequence, or
/// kMinRolloutFrames ≤ frames ≤ kMaxRolloutFrames), else what is wrong with it.
std::string rollout_frames_problem(long long frames);

/// Version of what a rollout file holds (metric columns, summary attributes); part of
/// the pipeline's cache key so that files written by an older version are recomputed.
/// 2: training/test windows, tiered horizons, free-DOF kinetic energy, 1-ring STED,
///    per-DOF residual.
inline constexpr int kRolloutFormatVersion = 2;

struct RolloutOptions {
    int max_frames = 0;  ///< 0: the whole sequence; else at least kMinRolloutFrames
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

/// ConfigError if options.max_frames is invalid (rollout_frames_problem); IoError if
/// the sequence has fewer than kMinRolloutFrames frames.
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
