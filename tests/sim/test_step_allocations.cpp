// Heap allocations of the full-space step (FullSpaceSimulator::step: Newton over the free
// DOFs, CHOLMOD factorisation and solve): after the first frames, in which the solver's
// buffers and CHOLMOD's workspace grow to the scene's sizes, further frames allocate
// nothing, so the step causes no page-fault storm on the full-size scenes. CHOLMOD's own
// blocks (its permuted copy of A per factorisation, its solve workspace) come back from the
// cache in sparse_cholesky.cpp. Not covered: at full size, with two OpenMP threads, every
// OpenMP region allocates libgomp's team descriptor (a few hundred bytes). The element loops
// open one per energy term per evaluation; CHOLMOD's supernodal factorisation opens one per
// supernode (about 800 per factorisation on the full cantilever, 2026-12-06). The small
// scenes here stay below kParallelElementThreshold and CHOLMOD's parallel sizes, so they
// open no region.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <cstdio>

#include "core/allocator.hpp"
#include "sim/full_space_simulator.hpp"
#include "support/heap_counter.hpp"

namespace lb {
namespace {

class StepAllocations : public ::testing::TestWithParam<const char*> { };

/// Heap allocations in frames 4-11 of the scene's small variant (after frames 1-3 warm up).
void expect_no_steady_allocations(const char* scene_name, int lagged_factor_cg)
{
    keep_freed_memory();
    const Scene scene =
        load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml", {"small"});
    const PhysicsModel model(physics_spec(scene));
    NewtonOptions newton = scene.newton;
    newton.lagged_factor_cg = lagged_factor_cg;
    FullSpaceSimulator sim(model, newton);
    const SequenceSpec& seq = scene.sequences.front();
    const BoundaryTrajectory traj = scene.trajectory(seq);
    ASSERT_GE(seq.frames, 12) << scene_name;
    VectorXd x_prev2 = model.rest_state(), x_prev = x_prev2, x;
    int iterations = 0;
    auto advance = [&](int t) {
        const SolveSummary s = sim.step(x_prev, x_prev2, traj.targets[size_t(t)], x);
        EXPECT_TRUE(s.converged()) << scene_name << " frame " << t << ": " << s.brief();
        iterations += s.iterations;
        x_prev2.swap(x_prev);
        x_prev = x;
    };
    long warm_up = 0;
    {
        testing::HeapCounter counter;
        for (int t = 1; t <= 3; ++t) advance(t);
        warm_up = counter.count();
    }
    iterations = 0;
    testing::HeapCounter counter;
    for (int t = 4; t <= 11; ++t) advance(t);
    const long steady = counter.count();
    std::printf("[ %s%s: %ld allocations in frames 1-3, %ld in frames 4-11 (%d Newton iterations) ]\n", scene_name,
                lagged_factor_cg > 0 ? " (lagged factor CG)" : "", warm_up, steady, iterations);
    EXPECT_GT(warm_up, 0) << "the counter sees the solver's allocations";
    EXPECT_GT(iterations, 8) << "the frames are real dynamic steps";
    EXPECT_EQ(steady, 0) << scene_name;
}

TEST_P(StepAllocations, NothingAllocatedAfterTheFirstFrames)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    expect_no_steady_allocations(GetParam(), 0);
}

TEST_P(StepAllocations, NothingAllocatedAfterTheFirstFramesWithLaggedFactorCg)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    expect_no_steady_allocations(GetParam(), 8);
}

INSTANTIATE_TEST_SUITE_P(SmallScenes, StepAllocations,
                         ::testing::Values("cloth", "cantilever", "rods_translate", "rods_rotate", "bunny_ears",
                                           "armadillo"),
                         [](const auto& info) { return std::string(info.param); });

} // namespace
} // namespace lb
