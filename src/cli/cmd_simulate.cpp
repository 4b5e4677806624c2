#include <cstdio>

#include "cli/commands.hpp"
#include "core/log.hpp"
#include "eval/rollout.hpp"
#include "core/timer.hpp"
#include "io/atomic_file.hpp"
#include "scene/scene.hpp"
#include "sim/dataset.hpp"

namespace lb::cli {

void register_simulate(CLI::App& app)
{
    struct Args {
        std::string scene;
        std::string variant;
        std::string output;
        int max_frames = 0;
        bool allow_nonconvergence = false;
        bool check = false;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("simulate", "Simulate every sequence of a scene in full space and write an HDF5 dataset");
    cmd->add_option("scene", args->scene, "Scene TOML file (experiments/scenes/*.toml)")->required();
    cmd->add_option("--variant", args->variant, "Scene variant, e.g. 'small'");
    cmd->add_option("-o,--output", args->output, "Output HDF5 file (required unless --check)");
    cmd->add_option("--max-frames", args->max_frames, "Simulate at most this many frames per sequence (0: all)")
        ->check(CLI::Range(0, int(kMaxRolloutFrames)));
    cmd->add_flag("--allow-nonconvergence", args->allow_nonconvergence,
                  "Record Newton failures and continue instead of stopping");
    cmd->add_flag("--check", args->check, "Validate the scene, print its summary and simulate nothing");
    cmd->callback([args] {
        Timer timer;
        if (!args->check) check_output_path(args->output, "-o");
        const Scene scene = load_scene(args->scene, {args->variant});
        if (args->check) {
            std::printf("scene '%s'%s: %ld vertices, %ld elements, %zu Dirichlet vertices, %zu sequences, dt %.4g s; "
                        "valid, nothing simulated\n",
                        scene.name.c_str(), scene.variant.empty() ? "" : (" (" + scene.variant + ")").c_str(),
                        long(scene.mesh.num_vertices()), long(scene.mesh.elements.rows()), scene.bc_indices.size(),
                        scene.sequences.size(), scene.dt);
            return;
        }
        log_info("scene '%s'%s: %ld vertices, %ld elements, %zu Dirichlet vertices, %zu sequences, dt %.4g s",
                 scene.name.c_str(), scene.variant.empty() ? "" : (" (" + scene.variant + ")").c_str(),
                 long(scene.mesh.num_vertices()), long(scene.mesh.elements.rows()), scene.bc_indices.size(),
                 scene.sequences.size(), scene.dt);
        SimulateOptions options;
        options.max_frames = args->max_frames;
        options.fail_on_nonconvergence = !args->allow_nonconvergence;
        options.progress = log_level() >= LogLevel::Info;
        const Dataset data = simulate_scene(scene, options);
        save_dataset(data, args->output);
        long frames = 0;
        for (const auto& s : data.sequences) frames += long(s.num_frames());
        std::printf("wrote %s: %zu sequences, %ld frames, %.1f s\n", args->output.c_str(),
                    data.sequences.size(), frames, timer.seconds());
    });
}

void register_info(CLI::App& app)
{
    auto path = std::make_shared<std::string>();
    CLI::App* cmd = app.add_subcommand("info", "Describe a latentbench HDF5 dataset, autoencoder or method artefact "
                                               "(with its training curve)");
    cmd->add_option("file", *path, "Dataset, autoencoder or artefact HDF5 file")->required();
    cmd->callback([path] {
        if (describe_training_file(*path)) return;
        const Dataset data = load_dataset(*path);
        std::printf("scene %s%s, %s, %ld vertices, %ld elements, %zu Dirichlet, dt %.4g\n",
                    data.scene_name.c_str(), data.variant.empty() ? "" : (" (" + data.variant + ")").c_str(),
                    to_string(data.physics.mesh.kind).c_str(), long(data.physics.mesh.num_vertices()),
                    long(data.physics.mesh.elements.rows()), data.physics.bc_indices.size(), data.physics.dt);
        for (const auto& s : data.sequences) {
            std::printf("  %-16s %5ld frames (train %d), max Newton it %.0f, max residual %.2e\n", s.name.c_str(),
                        long(s.num_frames()), s.train_frames, s.newton.col(0).maxCoeff(), s.newton.col(1).maxCoeff());
        }
    });
}

} // namespace lb::cli
