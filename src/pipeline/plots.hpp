#pragma once
// Figures of a suite: scripts/plot_rollouts.py (RMSE, boundary violation and
// kinetic energy per frame, one figure per sequence), scripts/plot_filmstrip.py
// (frames of every method beside the ground truth) and scripts/plot_video.py (an
// MP4 of every method beside the ground truth), run with Debian's /usr/bin/python3
// through an argument vector (core/process.hpp), never a shell.
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

struct VideoOptions {
    std::string output;    ///< the MP4 to write (atomically, by the script)
    std::string log_path;  ///< the script's messages are appended here
    int max_frames = 450;  ///< longer sequences are subsampled
};

/// One side-by-side MP4 of a scene's first evaluated sequence: the ground truth and
/// every method except the reference simulator `full_space` (which is the ground
/// truth's solver). Error naming the scene and the log on failure, or if ffmpeg is
/// missing.
void video_scene(const SceneResult& scene, const VideoOptions& options);

} // namespace lb
