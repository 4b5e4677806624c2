#pragma once
// Figures of a suite: scripts/plot_rollouts.py (RMSE, boundary violation and
// kinetic energy per frame, one figure per sequence) and scripts/plot_filmstrip.py
// (frames of every method beside the ground truth), run with Debian's
// /usr/bin/python3 through an argument vector (core/process.hpp), never a shell.
#include <string>
#include <vector>

#include "pipeline/report.hpp"

namespace lb {

struct PlotOptions {
    std::string figures_dir;
    std::string log_path;  ///< the scripts' messages are appended here
    bool filmstrips = true;
};

/// The PNG files written for one scene. Error naming the scene and the log on failure.
std::vector<std::string> plot_scene(const SceneResult& scene, const PlotOptions& options);

} // namespace lb
