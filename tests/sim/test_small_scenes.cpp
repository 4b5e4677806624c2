// Newton converges on every frame of every small scene.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include "sim/dataset.hpp"

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

INSTANTIATE_TEST_SUITE_P(Catalogue, SmallScene,
                         ::testing::Values("cloth", "cantilever", "rods_translate", "rods_rotate", "armadillo",
                                           "bunny_ears"));

} // namespace
} // namespace lb
