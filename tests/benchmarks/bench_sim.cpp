// One full-space implicit-Euler step per scene (Table 1's "Simulation" column):
//   sim_step/<scene>         the full-size scene (the paper's Table 1 row)
//   sim_step/<scene>_small   its small variant
//   sim_phase/<scene>/<phase>  the full-size armadillo's and bunny's step taken apart, at a
//                            mid-rollout state: assemble (the exact Hessian over the free
//                            DOFs), factorize (CHOLMOD's numeric LLᵀ, analysis reused), solve
//                            (one triangular solve pair), value_gradient (one line-search
//                            evaluation); where a step's time goes (a step costs about
//                            newton_it × (assemble + factorize + solve) plus the line search)
// scripts/make_report.py performance sets the full-size rows beside the paper's column. Each iteration advances the simulation by one frame of
// the scene's first sequence (after a few warm-up frames), so the measured
// steps are real dynamic steps. Counters: Newton iterations per step, DOFs,
// Hessian non-zeros, and sys_share, the process's kernel CPU time over the loop's wall
// time (page faults, thread wake-ups: issue 41's "sys time under 10 % of wall").
// Full-size Armadillo/Bunny need scripts/prepare_meshes.
#include "lb_paths.hpp"
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <memory>

#include "core/error.hpp"
#include "core/log.hpp"
#include "sim/full_space_simulator.hpp"
#include "solver/sparse_cholesky.hpp"

namespace lb {
namespace {

/// The process's kernel CPU time so far, in seconds.
double system_seconds()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_stime.tv_sec) + 1e-6 * double(u.ru_stime.tv_usec);
}

/// Wall time and kernel CPU time from construction: a timed loop's sys_share counter.
class LoopClock {
public:
    double wall_seconds() const
    {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - m_wall0).count();
    }
    /// Kernel CPU time over wall time since construction (0 if no time passed).
    double sys_share() const
    {
        const double wall = wall_seconds();
        return wall > 0.0 ? (system_seconds() - m_sys0) / wall : 0.0;
    }

private:
    double m_sys0 = system_seconds();
    std::chrono::steady_clock::time_point m_wall0 = std::chrono::steady_clock::now();
};

/// A scene's full-space simulation, stepped along its first sequence.
struct Stepper {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<PhysicsModel> model;
    std::unique_ptr<FullSpaceSimulator> sim;
    BoundaryTrajectory traj;
    int frames = 0;
    VectorXd x_prev2, x_prev, x;
    int t = 1;

    static constexpr int kWarmup = 5;

    /// After kWarmup steps; nullptr (with the state's error set) when the scene does not load.
    static std::unique_ptr<Stepper> make(benchmark::State& state, const std::string& scene_name,
                                         const std::string& variant, int lagged_factor_cg = -1)
    {
        set_log_level(LogLevel::Quiet);
        auto s = std::make_unique<Stepper>();
        try {
            s->scene = std::make_unique<Scene>(
                load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml", {variant}));
        } catch (const Error& e) {
            state.SkipWithError(e.what());
            return nullptr;
        }
        s->model = std::make_unique<PhysicsModel>(physics_spec(*s->scene));
        if (lagged_factor_cg >= 0) s->scene->newton.lagged_factor_cg = lagged_factor_cg;
        s->sim = std::make_unique<FullSpaceSimulator>(*s->model, s->scene->newton);
        const SequenceSpec& seq = s->scene->sequences.front();
        s->traj = s->scene->trajectory(seq);
        s->frames = seq.frames;
        s->x_prev2 = s->model->rest_state();
        s->x_prev = s->x_prev2;
        for (int i = 0; i < kWarmup; ++i) s->advance();
        return s;
    }
    SolveSummary advance()
    {
        const SolveSummary s = sim->step(x_prev, x_prev2, traj.targets[size_t(t)], x);
        x_prev2.swap(x_prev);
        x_prev = x;
        t = t + 1 < frames ? t + 1 : 1;
        return s;
    }
};

void sim_step(benchmark::State& state, const std::string& scene_name, const std::string& variant,
              int lagged_factor_cg = -1)
{
    const std::unique_ptr<Stepper> s = Stepper::make(state, scene_name, variant, lagged_factor_cg);
    if (!s) return;
    long iterations = 0, steps = 0, factorizations = 0, cg_iterations = 0;
    const LoopClock clock;
    for (auto _ : state) {
        const SolveSummary r = s->advance();
        if (!r.converged()) {
            state.SkipWithError(("Newton failed: " + r.brief()).c_str());
            break;
        }
        iterations += r.iterations;
        factorizations += r.factorizations;
        cg_iterations += r.cg_iterations;
        ++steps;
        benchmark::DoNotOptimize(s->x.data());
    }
    state.counters["newton_it"] = steps ? double(iterations) / double(steps) : 0.0;
    state.counters["factorizations"] = steps ? double(factorizations) / double(steps) : 0.0;
    state.counters["cg_it"] = steps ? double(cg_iterations) / double(steps) : 0.0;
    state.counters["dofs"] = double(s->model->num_dofs());
    state.counters["nnz"] = double(s->sim->newton().assembler().matrix().nonZeros());
    state.counters["sys_share"] = clock.sys_share();
}

enum class Phase { Assemble, Factorize, Solve, ValueGradient };

void sim_phase(benchmark::State& state, const std::string& scene_name, Phase phase)
{
    const std::unique_ptr<Stepper> s = Stepper::make(state, scene_name, "");
    if (!s) return;
    // The last step's potential at its solution: the state a Newton iteration sees.
    const EnergySum& terms = s->sim->potential().terms();
    HessianAssembler assembler(s->model->dof_to_unknown(), terms);
    assembler.assemble(terms, s->x, false);
    SparseCholesky cholesky;
    cholesky.analyze(assembler.matrix());
    if (cholesky.factorize(assembler.matrix()) != FactorStatus::Success) {
        state.SkipWithError(("factorisation failed: " + cholesky.message()).c_str());
        return;
    }
    const VectorXd b = VectorXd::Ones(assembler.num_unknowns());
    VectorXd dx, g(s->x.size());
    const LoopClock clock;
    for (auto _ : state) {
        switch (phase) {
        case Phase::Assemble: assembler.assemble(terms, s->x, false); break;
        case Phase::Factorize: benchmark::DoNotOptimize(cholesky.factorize(assembler.matrix())); break;
        case Phase::Solve: cholesky.solve(b, dx); break;
        case Phase::ValueGradient: benchmark::DoNotOptimize(terms.value_gradient(s->x, g)); break;
        }
        benchmark::ClobberMemory();
    }
    state.counters["nnz"] = double(assembler.matrix().nonZeros());
    state.counters["sys_share"] = clock.sys_share();
    if (phase == Phase::Factorize) {
        state.counters["factor_nnz"] = cholesky.factor_nonzeros();
        // over wall time (Google Benchmark's rates divide by the main thread's CPU time)
        state.counters["GFLOP_per_s"] =
            1e-9 * cholesky.factorization_flops() * double(state.iterations()) / clock.wall_seconds();
    }
}

#define LB_SCENE_BENCH(name)                                                                            \
    BENCHMARK_CAPTURE(sim_step, name, #name, "")->Unit(benchmark::kMillisecond)->MinTime(3.0);          \
    BENCHMARK_CAPTURE(sim_step, name##_small, #name, "small")->Unit(benchmark::kMillisecond)->MinTime(1.0)

// The full-size solids with NewtonOptions::lagged_factor_cg (scene key [solver]
// lagged_factor_cg): CG on the last factor before each new factorisation.
BENCHMARK_CAPTURE(sim_step, armadillo_lagged_cg4, "armadillo", "", 4)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK_CAPTURE(sim_step, armadillo_lagged_cg8, "armadillo", "", 8)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK_CAPTURE(sim_step, bunny_ears_lagged_cg4, "bunny_ears", "", 4)->Unit(benchmark::kMillisecond)->MinTime(3.0);
BENCHMARK_CAPTURE(sim_step, bunny_ears_lagged_cg8, "bunny_ears", "", 8)->Unit(benchmark::kMillisecond)->MinTime(3.0);

LB_SCENE_BENCH(cloth);
LB_SCENE_BENCH(cantilever);
LB_SCENE_BENCH(rods_translate);
LB_SCENE_BENCH(rods_rotate);
LB_SCENE_BENCH(armadillo);
LB_SCENE_BENCH(bunny_ears);

#define LB_PHASE_BENCH(scene, phase, value)                                                            \
    BENCHMARK_CAPTURE(sim_phase, scene##_##phase, #scene, value)                                          \
        ->Name("sim_phase/" #scene "/" #phase)->Unit(benchmark::kMillisecond)->MinTime(1.0)
#define LB_PHASES(scene)                                     \
    LB_PHASE_BENCH(scene, assemble, Phase::Assemble);        \
    LB_PHASE_BENCH(scene, factorize, Phase::Factorize);      \
    LB_PHASE_BENCH(scene, solve, Phase::Solve);              \
    LB_PHASE_BENCH(scene, value_gradient, Phase::ValueGradient)

LB_PHASES(armadillo);
LB_PHASES(bunny_ears);

} // namespace
} // namespace lb
