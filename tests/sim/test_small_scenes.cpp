// Newton converges on every frame of every small scene.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include "sim/dataset.hpp"
#include "sim/full_space_simulator.hpp"

namespace lb {
namespace {

class SmallScene : public ::testing::TestWithParam<const char*> { };

TEST_P(SmallScene, NewtonConvergesEveryFrame)
{
    const Scene scene =
        load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + GetParam() + ".toml", {"small"});
    SimulateOptions options;
    options.progress = false;
    options.fail_on_nonconvergence = false;
    const Dataset data = simulate_scene(scene, options);
    ASSERT_EQ(data.sequences.size(), scene.sequences.size());
    for (size_t k = 0; k < data.sequences.size(); ++k) {
        const SequenceData& s = data.sequences[k];
        EXPECT_EQ(s.num_frames(), scene.sequences[k].frames);
        EXPECT_TRUE(s.positions.allFinite());
        // Column 1 holds the scaled residual; the solver's default tolerance is
        // NewtonOptions::gradient_tolerance unless the scene sets [solver].
        const double tol = scene.newton.gradient_tolerance;
        for (Index t = 1; t < s.num_frames(); ++t) {
            ASSERT_LT(s.newton(t, 0), scene.newton.max_iterations)
                << GetParam() << " sequence " << s.name << " frame " << t << " hit the iteration cap";
            ASSERT_LE(s.newton(t, 1), 1e3 * tol)
                << GetParam() << " sequence " << s.name << " frame " << t << " residual " << s.newton(t, 1);
        }
        // The boundary vertices follow their prescribed trajectory exactly (hard constraints).
        const Index last = s.num_frames() - 1;
        for (size_t b = 0; b < data.physics.bc_indices.size(); ++b) {
            const int i = data.physics.bc_indices[b];
            EXPECT_NEAR((s.positions.row(last).segment<3>(3 * i) - s.bc_positions.row(last).segment<3>(3 * Index(b))).norm(),
                        0.0, 1e-12);
        }
    }
}

// NewtonOptions::lagged_factor_cg: CG on the last factor replaces most factorisations and
// reaches the direct solves' states. Both stop at the same gradient tolerance, so they agree
// to within what that tolerance itself decides: the yardstick is how far the direct solves
// move when the tolerance is ten times looser (both about 1e-9 of the diagonal after 39
// frames on the solids and rods, 2026-12-07). Not the cloth: its small scene amplifies any
// difference about 2.7-fold per frame (1e-10 of the diagonal at frame 5 grows to 2e-2 by
// frame 39 even with CG solved to 1e-5), so the option is for the solids and rods.
class LaggedFactorCg : public ::testing::TestWithParam<const char*> { };

TEST_P(LaggedFactorCg, ReachesTheDirectSolvesStates)
{
    const Scene scene =
        load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + GetParam() + ".toml", {"small"});
    const PhysicsModel model(physics_spec(scene));
    const SequenceSpec& seq = scene.sequences.front();
    const BoundaryTrajectory traj = scene.trajectory(seq);
    const int frames = std::min(seq.frames, 40);
    struct Run {
        MatrixXd states;
        int iterations = 0, factorizations = 0, cg_iterations = 0;
    };
    auto run = [&](int lagged_factor_cg, double tolerance_factor = 1.0) {
        NewtonOptions newton = scene.newton;
        newton.lagged_factor_cg = lagged_factor_cg;
        newton.gradient_tolerance *= tolerance_factor;
        FullSpaceSimulator sim(model, newton);
        Run r;
        r.states.resize(frames, model.num_dofs());
        VectorXd x_prev2 = model.rest_state(), x_prev = x_prev2, x;
        r.states.row(0) = x_prev.transpose();
        for (int t = 1; t < frames; ++t) {
            const SolveSummary s = sim.step(x_prev, x_prev2, traj.targets[size_t(t)], x);
            EXPECT_TRUE(s.converged()) << GetParam() << " lagged_factor_cg " << lagged_factor_cg << " frame " << t
                                       << ": " << s.brief();
            r.iterations += s.iterations;
            r.factorizations += s.factorizations;
            r.cg_iterations += s.cg_iterations;
            r.states.row(t) = x.transpose();
            x_prev2.swap(x_prev);
            x_prev = x;
        }
        return r;
    };
    const Run direct = run(0), lagged = run(8), looser = run(0, 10.0);
    EXPECT_EQ(direct.cg_iterations, 0);
    EXPECT_GE(direct.factorizations, direct.iterations) << GetParam();
    EXPECT_GT(lagged.cg_iterations, 0) << GetParam();
    EXPECT_LT(lagged.factorizations, direct.factorizations / 2) << GetParam();
    const double gap = (lagged.states - direct.states).cwiseAbs().maxCoeff() / model.length_scale();
    const double yardstick = (looser.states - direct.states).cwiseAbs().maxCoeff() / model.length_scale();
    std::printf("[ %s, %d frames: direct %d it, %d factorisations; lagged CG %d it, %d factorisations, %d CG it; "
                "max |x_lagged - x_direct| = %.2e of the diagonal; direct at a 10x looser tolerance: %.2e ]\n",
                GetParam(), frames - 1, direct.iterations, direct.factorizations, lagged.iterations,
                lagged.factorizations, lagged.cg_iterations, gap, yardstick);
    EXPECT_LT(gap, 10.0 * yardstick + 1e-8) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Catalogue, SmallScene,
                         ::testing::Values("cloth", "cantilever", "rods_translate", "rods_rotate", "armadillo",
                                           "bunny_ears"));

INSTANTIATE_TEST_SUITE_P(SolidsAndRods, LaggedFactorCg,
                         ::testing::Values("cantilever", "rods_translate", "rods_rotate", "armadillo", "bunny_ears"));

} // namespace
} // namespace lb
