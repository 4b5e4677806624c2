// Energy::add_value_gradient_columns (the training pass vectorised over the samples of a
// batch) against add_value_gradient (vectorised over the elements) on each sample: the same
// values and gradients bit for bit, for every energy with a column pass, on the cloth's,
// the cantilever's and the rods' materials. The samples are independently perturbed states,
// so a lane that read another lane's positions, or a scatter into the wrong column, fails.
#include "lb_paths.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"
#include "scene/scene.hpp"
#include "sim/physics_model.hpp"

namespace lb {
namespace {

constexpr int W = Energy::kColumnLanes;

void check_scene(const std::string& scene_name, Mesh mesh, int expected_terms)
{
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + scene_name + ".toml");
    PhysicsSpec spec = physics_spec(scene);
    spec.mesh = std::move(mesh);
    spec.bc_indices = {0};
    const PhysicsModel model(spec);
    const Index n = model.num_dofs();
    Rng rng(11);
    std::vector<VectorXd> x;
    for (int l = 0; l < W; ++l)
        x.push_back(lb::testing::perturbed_state(model.mesh().rest_positions, 0.05 * model.length_scale(), rng));
    VectorXd X(n * W), G(n * W);
    for (int l = 0; l < W; ++l) {
        for (Index r = 0; r < n; ++r) X[r * W + l] = x[size_t(l)][r];
    }
    int terms = 0;
    for (const auto& term : model.elastic_terms()) {
        ASSERT_TRUE(term->has_column_pass()) << term->name();
        ++terms;
        // Start from a non-zero gradient, as inside the incremental potential (inertia first).
        std::vector<VectorXd> g(W);
        for (int l = 0; l < W; ++l) g[size_t(l)] = rng.uniform_vector(n, -1.0, 1.0);
        for (int l = 0; l < W; ++l) {
            for (Index r = 0; r < n; ++r) G[r * W + l] = g[size_t(l)][r];
        }
        const double weight = 0.7;
        double values[W] = {};
        term->add_value_gradient_columns(X.data(), weight, G.data(), values);
        for (int l = 0; l < W; ++l) {
            double expected = 0.0;
            // The serial element pass, as the training losses run it: inside a parallel region.
#pragma omp parallel num_threads(1)
            expected = term->add_value_gradient(x[size_t(l)], weight, g[size_t(l)]);
            EXPECT_EQ(values[l], expected) << scene_name << " " << term->name() << " sample " << l;
            Index differing = 0;
            for (Index r = 0; r < n; ++r) differing += G[r * W + l] != g[size_t(l)][r];
            EXPECT_EQ(differing, 0) << scene_name << " " << term->name() << " sample " << l << ": gradient entries differ";
        }
        EXPECT_GT(std::abs(values[0]), 0.0) << term->name() << ": a zero energy checks little";
    }
    EXPECT_EQ(terms, expected_terms) << scene_name;
}

TEST(ColumnLanes, ClothTermsMatchTheElementPass)
{
    ClothGridOptions o;
    o.nx = 13;  // 12 × 9 quads: neither the triangles nor the hinges fill whole blocks of 8
    o.ny = 10;
    check_scene("cloth", make_cloth_grid(o), 2);
}

TEST(ColumnLanes, SolidTermsMatchTheElementPass)
{
    TetBeamOptions o;
    o.nx = 5;
    o.ny = o.nz = 2;
    check_scene("cantilever", make_tet_beam(o), 1);
}

TEST(ColumnLanes, RodTermsMatchTheElementPass)
{
    RodBundleOptions o;
    o.num_rods_x = 3;
    o.num_rods_y = 2;
    check_scene("rods_translate", make_rod_bundle(o), 2);
}

TEST(ColumnLanes, EnergiesWithoutAColumnPassRefuseIt)
{
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/cloth.toml");
    const PhysicsModel model(physics_spec(scene));
    EXPECT_FALSE(model.gravity()->has_column_pass());
    double values[W] = {};
    VectorXd X = VectorXd::Zero(model.num_dofs() * W), G = X;
    EXPECT_THROW(model.gravity()->add_value_gradient_columns(X.data(), 1.0, G.data(), values), Error);
}

} // namespace
} // namespace lb
