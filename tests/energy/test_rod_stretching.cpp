#include "energy/rod_stretching.hpp"

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_derivatives_near_rest;
using testing::check_element_hessians;
using testing::check_rigid_invariance_near_rest;
using testing::small_bundle;

constexpr double kYoungs = 1e7;   // Pa
constexpr double kRadius = 1e-3;  // m
constexpr double kSegment = 0.1;  // m


TEST(RodStretching, GradientAndHessianMatchFiniteDifferences)
{
    const Mesh mesh = small_bundle();
    const RodStretching energy(mesh.rest_positions, mesh.elements, kYoungs, kRadius);
    Rng rng(43);
    EXPECT_TRUE(check_derivatives_near_rest(energy, mesh.rest_positions, 0.3 * kSegment, kSegment, rng));
}

TEST(RodStretching, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_bundle();
    const RodStretching energy(mesh.rest_positions, mesh.elements, kYoungs, kRadius);
    Rng rng(47);
    EXPECT_TRUE(check_rigid_invariance_near_rest(energy, mesh.rest_positions, 0.2 * kSegment, rng));
}

TEST(RodStretching, ElementHessiansSymmetricAndPsdAfterProjection)
{
    const Mesh mesh = small_bundle();
    const RodStretching energy(mesh.rest_positions, mesh.elements, kYoungs, kRadius);
    Rng rng(53);
    VectorXd x = 0.7 * flatten(mesh.rest_positions); // compressed edges: indefinite
    x += rng.uniform_vector(x.size(), -0.1 * kSegment, 0.1 * kSegment);
    Index indefinite = 0;
    EXPECT_TRUE(check_element_hessians(energy, x, &indefinite));
    EXPECT_GT(indefinite, 0);
}

TEST(RodStretching, UniformStretchMatchesClosedForm)
{
    const Mesh mesh = small_bundle();
    const RodStretching energy(mesh.rest_positions, mesh.elements, kYoungs, kRadius);
    const double ks = kYoungs * M_PI * kRadius * kRadius;
    EXPECT_NEAR(energy.stretching_stiffness(), ks, 1e-12 * ks);
    const double total_length = 4 * 0.5;
    for (double s : {0.9, 1.0, 1.2}) {
        // Scaling about any point stretches every edge by s: E = ½ k_s (s − 1)² L_total.
        const double expected = 0.5 * ks * (s - 1) * (s - 1) * total_length;
        EXPECT_NEAR(energy.value(s * flatten(mesh.rest_positions)), expected, 1e-10 * ks * total_length) << s;
    }
}

TEST(RodStretching, RejectsZeroLengthEdge)
{
    MatrixX3d rest = MatrixX3d::Zero(2, 3);
    MatrixXi edge(1, 2);
    edge << 0, 1;
    EXPECT_THROW(RodStretching(rest, edge, kYoungs, kRadius), Error);
    MatrixXi wrong_shape(1, 3);
    wrong_shape << 0, 1, 1;
    EXPECT_THROW(RodStretching(rest, wrong_shape, kYoungs, kRadius), Error);
}

} // namespace
} // namespace lb
