// Energy::add_value_gradient (one pass, used by the training losses) against value() and
// gradient() with the cloth's and the cantilever's materials on generated meshes large
// enough (more elements than kParallelElementThreshold) for the parallel branch at the
// top level, and the serial branch inside a parallel region. The small-mesh tests of every energy run the
// same check through check_energy_gradient.
#include "lb_paths.hpp"

#include <gtest/gtest.h>

#include "core/parallel.hpp"
#include "energy/dirichlet_penalty.hpp"
#include "energy/inertia_energy.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"
#include "scene/scene.hpp"
#include "sim/physics_model.hpp"

namespace lb {
namespace {

void check_scene(const std::string& scene_name, Mesh mesh)
{
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml");
    PhysicsSpec spec = physics_spec(scene);
    spec.mesh = std::move(mesh);
    spec.bc_indices = {0};
    const PhysicsModel model(spec);
    Rng rng(7);
    const VectorXd x = lb::testing::perturbed_state(model.mesh().rest_positions, 0.02 * model.length_scale(), rng);
    bool large = false;
    for (const auto& term : model.elastic_terms()) {
        large |= term->num_elements() >= kParallelElementThreshold;
        EXPECT_TRUE(lb::testing::check_fused_value_gradient(*term, x)) << scene_name;
    }
    EXPECT_TRUE(lb::testing::check_fused_value_gradient(*model.gravity(), x)) << scene_name;
    // The vertex terms' whole-state passes (no per-vertex call), at a moved inertial target
    // and penalty targets.
    InertiaEnergy inertia(model.masses(), model.dt());
    inertia.set_x_tilde(lb::testing::perturbed_state(model.mesh().rest_positions, 0.02 * model.length_scale(), rng));
    EXPECT_TRUE(lb::testing::check_fused_value_gradient(inertia, x)) << scene_name;
    std::vector<int> boundary;
    for (int v = 0; v < int(model.mesh().num_vertices()); v += 7) boundary.push_back(v);
    DirichletPenalty penalty(boundary, 1e5);
    penalty.set_targets(MatrixX3d::Random(Index(boundary.size()), 3));
    EXPECT_TRUE(lb::testing::check_fused_value_gradient(penalty, x)) << scene_name;
    EXPECT_TRUE(large) << scene_name << ": no term reaches the parallel branch";
}

TEST(FusedValueGradient, LargeClothTerms)
{
    ClothGridOptions o;
    o.nx = o.ny = 40;  // 3,042 triangles, 4,485 hinges
    check_scene("cloth", make_cloth_grid(o));
}

TEST(FusedValueGradient, LargeSolidTerms)
{
    TetBeamOptions o;
    o.nx = 20;
    o.ny = o.nz = 5;  // 3,000 tetrahedra
    check_scene("cantilever", make_tet_beam(o));
}

} // namespace
} // namespace lb
