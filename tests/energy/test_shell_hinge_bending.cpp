#include "energy/shell_hinge_bending.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_derivatives_near_rest;
using testing::check_element_hessians;
using testing::check_energy_gradient;
using testing::check_energy_hessian;
using testing::check_rigid_invariance_near_rest;
using testing::perturbed_state;
using testing::small_cloth;

constexpr double kYoungs = 1e5;      // Pa
constexpr double kPoisson = 0.3;
constexpr double kThickness = 1e-3;  // m
constexpr double kCell = 0.1;        // m


TEST(ShellHingeBending, GradientAndHessianMatchFiniteDifferences)
{
    const Mesh mesh = small_cloth();
    const ShellHingeBending energy(mesh.rest_positions, shell_hinge_stencils(mesh.elements), kYoungs, kPoisson,
                                   kThickness);
    ASSERT_GT(energy.num_elements(), 0);
    Rng rng(29);
    EXPECT_TRUE(check_derivatives_near_rest(energy, mesh.rest_positions, 0.25 * kCell, kCell, rng));
}

TEST(ShellHingeBending, GradientAndHessianMatchFiniteDifferencesWithCurvedRest)
{
    // Rest state already bent (θ̄ ≠ 0): a cloth draped over a cylinder.
    Mesh mesh = small_cloth();
    for (Index i = 0; i < mesh.num_vertices(); ++i) {
        const double x = mesh.rest_positions(i, 0);
        mesh.rest_positions(i, 2) = 0.5 * (x - 0.2) * (x - 0.2);
    }
    const ShellHingeBending energy(mesh.rest_positions, shell_hinge_stencils(mesh.elements), kYoungs, kPoisson,
                                   kThickness);
    Rng rng(31);
    const VectorXd x = perturbed_state(mesh.rest_positions, 0.25 * kCell, rng);
    EXPECT_TRUE(check_energy_gradient(energy, x, kCell));
    EXPECT_TRUE(check_energy_hessian(energy, x, kCell));
    EXPECT_NEAR(energy.value(flatten(mesh.rest_positions)), 0.0, 1e-24);
}

TEST(ShellHingeBending, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_cloth();
    const ShellHingeBending energy(mesh.rest_positions, shell_hinge_stencils(mesh.elements), kYoungs, kPoisson,
                                   kThickness);
    Rng rng(37);
    EXPECT_TRUE(check_rigid_invariance_near_rest(energy, mesh.rest_positions, 0.2 * kCell, rng));
}

TEST(ShellHingeBending, ElementHessiansSymmetricAndPsdAfterProjection)
{
    const Mesh mesh = small_cloth();
    const ShellHingeBending energy(mesh.rest_positions, shell_hinge_stencils(mesh.elements), kYoungs, kPoisson,
                                   kThickness);
    Rng rng(41);
    Index indefinite = 0;
    EXPECT_TRUE(check_element_hessians(energy, perturbed_state(mesh.rest_positions, 0.3 * kCell, rng), &indefinite));
    EXPECT_GT(indefinite, 0);
}

// Two triangles (0, 1, 2) and (1, 0, 3) sharing the edge 0–1 along x, flat at rest.
MatrixX3d two_triangles()
{
    MatrixX3d rest(4, 3);
    rest << 0.0, 0.0, 0.0, 0.5, 0.0, 0.0, 0.2, 0.3, 0.0, 0.3, -0.4, 0.0;
    return rest;
}

MatrixX3d fold_vertex_3(const MatrixX3d& rest, double angle)
{
    MatrixX3d x = rest;
    x.row(3) = (Eigen::AngleAxisd(angle, Vector3d::UnitX()) * rest.row(3).transpose()).transpose();
    return x;
}

TEST(ShellHingeBending, SingleHingeFoldMatchesClosedForm)
{
    const MatrixX3d rest = two_triangles();
    MatrixXi triangles(2, 3);
    triangles << 0, 1, 2, 1, 0, 3;
    const MatrixXi hinges = shell_hinge_stencils(triangles);
    ASSERT_EQ(hinges.rows(), 1);
    EXPECT_EQ(hinges.row(0), Eigen::RowVector4i(0, 1, 2, 3));

    const ShellHingeBending energy(rest, hinges, kYoungs, kPoisson, kThickness);
    const double kb = kYoungs * std::pow(kThickness, 3) / (24 * (1 - kPoisson * kPoisson));
    EXPECT_NEAR(energy.bending_stiffness(), kb, 1e-15 * kb);
    const double edge = 0.5;
    const double area1 = 0.5 * 0.5 * 0.3, area2 = 0.5 * 0.5 * 0.4;
    for (double fold : {-1.2, -0.3, 0.05, 0.7, 2.0}) {
        const double expected = kb * fold * fold * 3 * edge * edge / (area1 + area2);
        EXPECT_NEAR(energy.value(flatten(fold_vertex_3(rest, fold))), expected, 1e-12 * expected) << fold;
    }
}

TEST(ShellHingeBending, FoldRelativeToFoldedRestAngle)
{
    const MatrixX3d flat = two_triangles();
    MatrixXi hinge(1, 4);
    hinge << 0, 1, 2, 3;
    const double rest_fold = 0.6;
    const ShellHingeBending energy(fold_vertex_3(flat, rest_fold), hinge, kYoungs, kPoisson, kThickness);
    EXPECT_NEAR(std::abs(energy.rest_angle(0)), rest_fold, 1e-12);
    const double w = energy.hinge_weight(0); // areas and edge unchanged by the fold
    for (double fold : {0.0, 0.2, 1.1}) {
        const double expected = w * (fold - rest_fold) * (fold - rest_fold);
        EXPECT_NEAR(energy.value(flatten(fold_vertex_3(flat, fold))), expected, 1e-12 * w) << fold;
    }
}

TEST(ShellHingeBending, RejectsDegenerateHinge)
{
    MatrixX3d rest = two_triangles();
    rest.row(2) << 0.25, 0.0, 0.0; // collinear with the edge
    MatrixXi hinge(1, 4);
    hinge << 0, 1, 2, 3;
    EXPECT_THROW(ShellHingeBending(rest, hinge, kYoungs, kPoisson, kThickness), Error);
}

} // namespace
} // namespace lb
