#pragma once
// The small variant of a shipped scene, simulated quietly for a test.
#include "lb_paths.hpp"
#include <algorithm>
#include <string>

#include "core/log.hpp"
#include "scene/scene.hpp"

namespace lb::testing {

/// The first `frames` frames of the small variant of experiments/scenes/<scene>.toml.
/// With `train_frames` ≥ 0 only the first sequence is kept and trained on its first
/// `train_frames` frames; otherwise every sequence is kept and its training split is
/// clamped to `frames`.
inline Dataset simulate_small_scene(const std::string& scene, int frames, int train_frames = -1)
{
    set_log_level(LogLevel::Quiet);
    Scene s = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene + ".toml", {"small"});
    if (train_frames >= 0) {
        s.sequences.resize(1);
        s.sequences[0].train_frames = train_frames;
    } else {
        for (auto& seq : s.sequences) seq.train_frames = std::min(seq.train_frames, frames);
    }
    SimulateOptions so;
    so.max_frames = frames;
    so.progress = false;
    return simulate_scene(s, so);
}

} // namespace lb::testing
