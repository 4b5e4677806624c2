// Energy::add_value_gradient (one pass, used by the training losses) against value() and
// gradient() with the cloth's and the cantilever's materials on generated meshes large
// enough (more elements than kParallelElementThreshold) for the parallel branch at the
// top level, and the serial branch inside a parallel region. The small-mesh tests of every energy run the
// same check through check_energy_gradient.
#include "lb_paths.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include "core/parallel.hpp"
#include "energy/dirichlet_penalty.hpp"
#include "energy/inertia_energy.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"
#include "scene/scene.hpp"
#include "sim/physics_model.hpp"

namespace lb {
namespace {

/// The scene's physics (materials, dt) on a generated mesh, vertex 0 fixed.
PhysicsModel model_on(const std::string& scene_name, Mesh mesh)
{
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml");
    PhysicsSpec spec = physics_spec(scene);
    spec.mesh = std::move(mesh);
    spec.bc_indices = {0};
    return PhysicsModel(spec);
}

void check_scene(const std::string& scene_name, Mesh mesh)
{
    const PhysicsModel model = model_on(scene_name, std::move(mesh));
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

/// value() and gradient() of every elastic term (what the simulator's Newton solve and the
/// metrics call) give the same numbers bit for bit at 1, 2 and 3 threads: the parallel branch
/// sums the element values in element order (an OpenMP reduction's partial sums would follow
/// the threads). add_value_gradient() too for the cloth's terms; its parallel branch is not
/// the lane-blocked serial pass of the tetrahedra (energy.cpp), and no caller reaches it.
void check_thread_count(const std::string& scene_name, Mesh mesh, bool fused_too)
{
    const PhysicsModel model = model_on(scene_name, std::move(mesh));
    Rng rng(8);
    const VectorXd x = lb::testing::perturbed_state(model.mesh().rest_positions, 0.02 * model.length_scale(), rng);
    const int threads_before = omp_get_max_threads();
    for (const auto& term : model.elastic_terms()) {
        ASSERT_GE(term->num_elements(), kParallelElementThreshold) << scene_name << " " << term->name();
        double value[3], fused[3];
        VectorXd gradient[3], fused_gradient[3];
        for (int t = 1; t <= 3; ++t) {
            omp_set_num_threads(t);
            value[t - 1] = term->value(x);
            gradient[t - 1] = term->gradient(x);
            fused_gradient[t - 1] = VectorXd::Zero(x.size());
            fused[t - 1] = term->add_value_gradient(x, 1.0, fused_gradient[t - 1]);
        }
        for (int t = 1; t < 3; ++t) {
            EXPECT_EQ(value[t], value[0]) << scene_name << " " << term->name() << ", " << t + 1 << " threads";
            EXPECT_TRUE((gradient[t].array() == gradient[0].array()).all()) << scene_name << " " << term->name();
            if (!fused_too) continue;
            EXPECT_EQ(fused[t], fused[0]) << scene_name << " " << term->name() << ", " << t + 1 << " threads";
            EXPECT_TRUE((fused_gradient[t].array() == fused_gradient[0].array()).all()) << scene_name << " " << term->name();
        }
    }
    omp_set_num_threads(threads_before);
}

TEST(FusedValueGradient, ThreadCountLeavesTheNumbersUnchanged)
{
    ClothGridOptions cloth;
    cloth.nx = cloth.ny = 40;
    check_thread_count("cloth", make_cloth_grid(cloth), true);
    TetBeamOptions beam;
    beam.nx = 20;
    beam.ny = beam.nz = 5;
    check_thread_count("cantilever", make_tet_beam(beam), false);
}

} // namespace
} // namespace lb
