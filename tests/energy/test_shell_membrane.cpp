#include "energy/shell_membrane.hpp"

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_derivatives_near_rest;
using testing::check_element_hessians;
using testing::check_rigid_invariance_near_rest;
using testing::small_cloth;

constexpr double kYoungs = 1e5;      // Pa
constexpr double kPoisson = 0.3;
constexpr double kThickness = 1e-3;  // m
constexpr double kCell = 0.1;        // m


TEST(ShellMembrane, GradientAndHessianMatchFiniteDifferences)
{
    const Mesh mesh = small_cloth();
    const ShellMembrane energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson, kThickness);
    Rng rng(3);
    EXPECT_TRUE(check_derivatives_near_rest(energy, mesh.rest_positions, 0.3 * kCell, kCell, rng));
}

TEST(ShellMembrane, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_cloth();
    const ShellMembrane energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson, kThickness);
    Rng rng(5);
    EXPECT_TRUE(check_rigid_invariance_near_rest(energy, mesh.rest_positions, 0.2 * kCell, rng));
}

TEST(ShellMembrane, ElementHessiansSymmetricAndPsdAfterProjection)
{
    const Mesh mesh = small_cloth();
    const ShellMembrane energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson, kThickness);
    Rng rng(17);
    VectorXd x = 0.7 * flatten(mesh.rest_positions); // compressed: indefinite membrane Hessians
    x += rng.uniform_vector(x.size(), -0.1 * kCell, 0.1 * kCell);
    Index indefinite = 0;
    EXPECT_TRUE(check_element_hessians(energy, x, &indefinite));
    EXPECT_GT(indefinite, 0);
}

TEST(ShellMembrane, UniformInPlaneStretchMatchesClosedForm)
{
    // A single triangle in a tilted plane, rest edge not aligned with any frame axis.
    const Matrix3d frame = Eigen::AngleAxisd(0.6, Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
    MatrixX3d planar(3, 3);
    planar << 0.0, 0.0, 0.0, 0.3, 0.1, 0.0, 0.05, 0.25, 0.0;
    const MatrixX3d rest = planar * frame.transpose();
    MatrixXi triangle(1, 3);
    triangle << 0, 1, 2;
    const ShellMembrane energy(rest, triangle, kYoungs, kPoisson, kThickness);
    const double area = 0.5 * (0.3 * 0.25 - 0.1 * 0.05);
    EXPECT_NEAR(energy.rest_area(0), area, 1e-15);

    for (const auto& [sx, sy] : {std::pair{1.2, 1.0}, std::pair{1.1, 0.9}, std::pair{0.8, 0.8}}) {
        // Stretch by (sx, sy) along the plane's own axes: G = diag((sx²−1)/2, (sy²−1)/2) in
        // that frame; ||G||² and tr G do not depend on the frame.
        MatrixX3d stretched = planar;
        stretched.col(0) *= sx;
        stretched.col(1) *= sy;
        const MatrixX3d x = stretched * frame.transpose();
        const double g1 = 0.5 * (sx * sx - 1), g2 = 0.5 * (sy * sy - 1);
        const double k = kYoungs * kThickness / (1 - kPoisson * kPoisson);
        const double expected =
            area * k * ((1 - kPoisson) * (g1 * g1 + g2 * g2) + kPoisson * (g1 + g2) * (g1 + g2)) / 2;
        EXPECT_NEAR(energy.value(flatten(x)), expected, 1e-10 * expected) << sx << " " << sy;
    }
}

TEST(ShellMembrane, RestStateStoresNoEnergy)
{
    const Mesh mesh = small_cloth();
    const ShellMembrane energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson, kThickness);
    EXPECT_NEAR(energy.value(flatten(mesh.rest_positions)), 0.0, 1e-24);
    // Round-off only: compare with the force scale k·t·cell of a unit strain.
    EXPECT_LT(energy.gradient(flatten(mesh.rest_positions)).cwiseAbs().maxCoeff(), 1e-12 * kYoungs * kThickness * kCell);
}

TEST(ShellMembrane, RejectsDegenerateTriangle)
{
    MatrixX3d rest(3, 3);
    rest << 0, 0, 0, 1, 0, 0, 2, 0, 0;
    MatrixXi triangle(1, 3);
    triangle << 0, 1, 2;
    EXPECT_THROW(ShellMembrane(rest, triangle, kYoungs, kPoisson, kThickness), Error);
    EXPECT_THROW(ShellMembrane(rest, triangle, kYoungs, kPoisson, 0.0), Error);
}

} // namespace
} // namespace lb
