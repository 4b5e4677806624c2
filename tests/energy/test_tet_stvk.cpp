#include "energy/tet_stvk.hpp"

#include <Eigen/LU>

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_element_hessians;
using testing::check_energy_gradient;
using testing::check_energy_hessian;
using testing::check_rigid_invariance;
using testing::perturbed_state;

constexpr double kYoungs = 1e6;   // Pa
constexpr double kPoisson = 0.3;

Mesh small_beam()
{
    TetBeamOptions options;
    options.nx = 3;
    options.ny = 2;
    options.nz = 2;
    options.size = Vector3d(0.3, 0.2, 0.2); // 0.1 m cells
    return make_tet_beam(options);
}
constexpr double kCell = 0.1; // m

TEST(TetStVK, GradientAndHessianMatchFiniteDifferences)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(7);
    for (int trial = 0; trial < 3; ++trial) {
        const VectorXd x = perturbed_state(mesh.rest_positions, 0.3 * kCell, rng);
        EXPECT_TRUE(check_energy_gradient(energy, x, kCell)) << "trial " << trial;
        EXPECT_TRUE(check_energy_hessian(energy, x, kCell)) << "trial " << trial;
    }
}

TEST(TetStVK, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(11);
    for (int trial = 0; trial < 3; ++trial) {
        EXPECT_TRUE(check_rigid_invariance(energy, perturbed_state(mesh.rest_positions, 0.2 * kCell, rng), rng));
    }
}

TEST(TetStVK, ElementHessiansSymmetricAndPsdAfterProjection)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(13);
    // Strong compression makes StVK indefinite, so the projection is exercised.
    VectorXd x = 0.6 * flatten(mesh.rest_positions);
    x += rng.uniform_vector(x.size(), -0.1 * kCell, 0.1 * kCell);
    Index indefinite = 0;
    EXPECT_TRUE(check_element_hessians(energy, x, &indefinite));
    EXPECT_GT(indefinite, 0) << "the state should make some element Hessians indefinite";
}

TEST(TetStVK, RestStateHasZeroEnergyAndGradient)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    const VectorXd x = flatten(mesh.rest_positions);
    EXPECT_NEAR(energy.value(x), 0.0, 1e-20);
    EXPECT_LT(energy.gradient(x).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(TetStVK, UniformStretchOfUnitCubeMatchesClosedForm)
{
    TetBeamOptions options;
    options.nx = options.ny = options.nz = 2;
    options.size = Vector3d::Ones();
    const Mesh cube = make_tet_beam(options);
    const TetStVK energy(cube.rest_positions, cube.elements, kYoungs, kPoisson);
    const LameParameters lame = lame_parameters(kYoungs, kPoisson);
    EXPECT_NEAR(lame.mu, kYoungs / (2 * (1 + kPoisson)), 1e-9);
    EXPECT_NEAR(lame.lambda, kYoungs * kPoisson / ((1 + kPoisson) * (1 - 2 * kPoisson)), 1e-9);

    for (double s : {0.7, 0.95, 1.1, 1.5}) {
        MatrixX3d deformed = cube.rest_positions;
        deformed.col(0) *= s;
        // G = diag((s² − 1)/2, 0, 0), V = 1 m³: E = μ G₁₁² + ½ λ G₁₁².
        const double g11 = 0.5 * (s * s - 1.0);
        const double expected = lame.mu * g11 * g11 + 0.5 * lame.lambda * g11 * g11;
        EXPECT_NEAR(energy.value(flatten(deformed)), expected, 1e-10 * expected) << "stretch " << s;
    }
}

TEST(TetStVK, RestVolumesSumToBoxVolume)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    double volume = 0.0;
    for (Index t = 0; t < energy.num_elements(); ++t) volume += energy.rest_volume(t);
    EXPECT_NEAR(volume, 0.3 * 0.2 * 0.2, 1e-14);
}

TEST(TetStVK, RejectsInvertedRestTetAndBadParameters)
{
    Mesh mesh = small_beam();
    MatrixXi inverted = mesh.elements;
    std::swap(inverted(0, 1), inverted(0, 2));
    EXPECT_THROW(TetStVK(mesh.rest_positions, inverted, kYoungs, kPoisson), Error);
    EXPECT_THROW(TetStVK(mesh.rest_positions, mesh.elements, -1.0, kPoisson), Error);
    EXPECT_THROW(TetStVK(mesh.rest_positions, mesh.elements, kYoungs, 0.5), Error);
    MatrixXi out_of_range = mesh.elements;
    out_of_range(0, 0) = int(mesh.num_vertices());
    EXPECT_THROW(TetStVK(mesh.rest_positions, out_of_range, kYoungs, kPoisson), Error);
}

} // namespace
} // namespace lb
