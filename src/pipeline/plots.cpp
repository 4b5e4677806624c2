#include "lb_paths.hpp"

#include "pipeline/plots.hpp"

#include <filesystem>
#include <fstream>

#include "core/error.hpp"
#include "core/process.hpp"

namespace lb {

namespace {

constexpr const char* kPython = "/usr/bin/python3";  // Debian's: it sees python3-matplotlib and python3-h5py
constexpr const char* kFfmpeg = "/usr/bin/ffmpeg";   // matplotlib's FFMpegWriter runs it

std::string script(const std::string& name) { return std::string(LB_SOURCE_DIR) + "/scripts/" + name; }

void run_or_throw(const std::vector<std::string>& argv, const ProcessOptions& io, const std::string& what,
                  const std::string& log)
{
    const int status = run_process(argv, io);
    if (status != 0) throw Error(what + " failed with status " + std::to_string(status) + " (see " + log + ")");
}

} // namespace

void video_scene(const SceneResult& r, const VideoOptions& options)
{
    if (!std::filesystem::exists(kPython))
        throw Error(std::string("videos need ") + kPython + " with matplotlib, h5py and numpy (scripts/run setup installs them)");
    if (!std::filesystem::exists(kFfmpeg))
        throw Error(std::string("[outputs] videos = true needs ") + kFfmpeg +
                    " (Debian package ffmpeg; scripts/run setup installs it), or set videos = false");
    std::filesystem::create_directories(std::filesystem::path(options.output).parent_path());
    std::vector<std::string> argv{kPython, script("plot_video.py"), r.dataset_file};
    for (const auto& m : r.methods) {
        if (m.method != "full_space") argv.push_back(m.rollout_file);
    }
    argv.insert(argv.end(), {"-o", options.output, "--title", r.label, "--max-frames", std::to_string(options.max_frames)});
    run_or_throw(argv, {options.log_path, options.log_path, /*append_stdout=*/true}, "video of " + r.label, options.log_path);
}

std::vector<std::string> plot_scene(const SceneResult& r, const PlotOptions& options)
{
    if (!std::filesystem::exists(kPython))
        throw Error(std::string("plots need ") + kPython + " with matplotlib, h5py and numpy (scripts/run setup installs them)");
    std::filesystem::create_directories(options.figures_dir);
    std::vector<std::string> figures;

    // plot_rollouts.py prints the paths it wrote, one per line.
    const std::string list = options.figures_dir + "/" + r.label + ".txt";
    std::vector<std::string> argv{kPython, script("plot_rollouts.py")};
    for (const auto& m : r.methods) argv.push_back(m.rollout_file);
    argv.insert(argv.end(), {"-o", options.figures_dir + "/" + r.label, "--title", r.label, "--train-frames",
                             std::to_string(r.train_frames)});
    run_or_throw(argv, {list, options.log_path, false}, "plotting " + r.label, options.log_path);
    {
        std::ifstream in(list);
        for (std::string line; std::getline(in, line);) {
            if (line.size() > 4 && line.compare(line.size() - 4, 4, ".png") == 0) figures.push_back(line);
        }
    }
    std::filesystem::remove(list);

    if (options.filmstrips) {
        const std::string png = options.figures_dir + "/" + r.label + "_filmstrip.png";
        std::vector<std::string> fargv{kPython, script("plot_filmstrip.py"), r.dataset_file};
        for (const auto& m : r.methods) {
            if (m.method != "full_space") fargv.push_back(m.rollout_file);
        }
        fargv.insert(fargv.end(), {"-o", png});
        run_or_throw(fargv, {options.log_path, options.log_path, /*append_stdout=*/true}, "filmstrip of " + r.label, options.log_path);
        figures.push_back(png);
    }
    return figures;
}

} // namespace lb
