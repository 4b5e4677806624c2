#include "energy/gravity_energy.hpp"

#include "energy_checks.hpp"

namespace lb {
namespace {

using testing::check_energy_gradient;

TEST(GravityEnergy, GradientMatchesFiniteDifferencesAndHessianIsZero)
{
    Rng rng(83);
    const VectorXd masses = rng.uniform_vector(6, 0.1, 2.0);
    const GravityEnergy energy(masses, GravityEnergy::standard_gravity());
    const VectorXd x = rng.uniform_vector(18, -1, 1);
    EXPECT_TRUE(check_energy_gradient(energy, x, 1.0));
    EXPECT_TRUE(energy.has_zero_hessian());
    EXPECT_EQ(MatrixXd(energy.hessian(x, false)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(GravityEnergy, IsMinusMassTimesGravityDotPosition)
{
    const VectorXd masses = (VectorXd(3) << 1.0, 2.0, 0.5).finished();
    const GravityEnergy energy(masses, Vector3d(0, 0, -9.81));
    VectorXd x = VectorXd::Zero(9);
    x[2] = 1.0;   // vertex 0 at z = 1
    x[5] = -2.0;  // vertex 1 at z = −2
    x[6] = 5.0;   // vertex 2 moved horizontally: no work
    EXPECT_NEAR(energy.value(x), 9.81 * (1.0 * 1.0 + 2.0 * -2.0), 1e-12);
    const VectorXd g = energy.gradient(x);
    EXPECT_NEAR(g[5], 2.0 * 9.81, 1e-12);
    EXPECT_NEAR(g[6], 0.0, 1e-15);
}

} // namespace
} // namespace lb
