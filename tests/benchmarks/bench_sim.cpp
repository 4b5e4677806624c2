// One full-space implicit-Euler step per scene (Table 1's "Simulation" column):
//   sim_step/<scene>         the full-size scene (the paper's Table 1 row)
//   sim_step/<scene>_small   its small variant
// scripts/make_report.py performance sets the full-size rows beside the paper's column. Each iteration advances the simulation by one frame of
// the scene's first sequence (after a few warm-up frames), so the measured
// steps are real dynamic steps. Counters: Newton iterations per step, DOFs,
// Hessian non-zeros. Full-size Armadillo/Bunny need scripts/prepare_meshes.
#include "lb_paths.hpp"
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "core/error.hpp"
#include "core/log.hpp"
#include "sim/full_space_simulator.hpp"

namespace lb {
namespace {

void sim_step(benchmark::State& state, const std::string& scene_name, const std::string& variant)
{
    set_log_level(LogLevel::Quiet);
    std::unique_ptr<Scene> scene;
    try {
        scene = std::make_unique<Scene>(
            load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml", {variant}));
    } catch (const Error& e) {
        state.SkipWithError(e.what());
        return;
    }
    const PhysicsModel model(physics_spec(*scene));
    FullSpaceSimulator sim(model, scene->newton);
    const SequenceSpec& seq = scene->sequences.front();
    const BoundaryTrajectory traj = scene->trajectory(seq);
    VectorXd x_prev2 = model.rest_state(), x_prev = x_prev2, x;
    constexpr int kWarmup = 5;
    int t = 1;
    auto advance = [&]() {
        const SolveSummary s = sim.step(x_prev, x_prev2, traj.targets[size_t(t)], x);
        x_prev2.swap(x_prev);
        x_prev = x;
        t = t + 1 < seq.frames ? t + 1 : 1;
        return s;
    };
    for (int i = 0; i < kWarmup; ++i) advance();
    long iterations = 0, steps = 0;
    for (auto _ : state) {
        const SolveSummary s = advance();
        if (!s.converged()) {
            state.SkipWithError(("Newton failed: " + s.brief()).c_str());
            break;
        }
        iterations += s.iterations;
        ++steps;
        benchmark::DoNotOptimize(x.data());
    }
    state.counters["newton_it"] = steps ? double(iterations) / double(steps) : 0.0;
    state.counters["dofs"] = double(model.num_dofs());
    state.counters["nnz"] = double(sim.newton().assembler().matrix().nonZeros());
}

#define LB_SCENE_BENCH(name)                                                                            \
    BENCHMARK_CAPTURE(sim_step, name, #name, "")->Unit(benchmark::kMillisecond)->MinTime(3.0);          \
    BENCHMARK_CAPTURE(sim_step, name##_small, #name, "small")->Unit(benchmark::kMillisecond)->MinTime(1.0)

LB_SCENE_BENCH(cloth);
LB_SCENE_BENCH(cantilever);
LB_SCENE_BENCH(rods_translate);
LB_SCENE_BENCH(rods_rotate);
LB_SCENE_BENCH(armadillo);
LB_SCENE_BENCH(bunny_ears);

} // namespace
} // namespace lb
