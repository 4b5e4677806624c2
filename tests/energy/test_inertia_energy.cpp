#include "energy/inertia_energy.hpp"

#include "core/error.hpp"
#include "energy_checks.hpp"

namespace lb {
namespace {

using testing::check_element_hessians;
using testing::check_energy_gradient;
using testing::check_energy_hessian;

constexpr double kDt = 1.0 / 30.0;  // s
constexpr int kVertices = 7;

TEST(InertiaEnergy, GradientAndHessianMatchFiniteDifferences)
{
    Rng rng(73);
    InertiaEnergy energy(rng.uniform_vector(kVertices, 0.1, 2.0), kDt);
    energy.set_x_tilde(rng.uniform_vector(3 * kVertices, -1, 1));
    const VectorXd x = rng.uniform_vector(3 * kVertices, -1, 1);
    EXPECT_TRUE(check_energy_gradient(energy, x, 1.0));
    EXPECT_TRUE(check_energy_hessian(energy, x, 1.0));
    EXPECT_TRUE(check_element_hessians(energy, x));
}

TEST(InertiaEnergy, MatchesMassWeightedQuadratic)
{
    Rng rng(79);
    const VectorXd masses = rng.uniform_vector(kVertices, 0.1, 2.0);
    InertiaEnergy energy(masses, kDt);
    const VectorXd x_tilde = rng.uniform_vector(3 * kVertices, -1, 1);
    energy.set_x_tilde(x_tilde);
    const VectorXd x = rng.uniform_vector(3 * kVertices, -1, 1);
    double expected = 0.0;
    for (int i = 0; i < kVertices; ++i) {
        expected += masses[i] * (x - x_tilde).segment<3>(3 * i).squaredNorm();
    }
    expected /= 2 * kDt * kDt;
    EXPECT_NEAR(energy.value(x), expected, 1e-12 * expected);
    EXPECT_NEAR(energy.value(x_tilde), 0.0, 1e-30);
    // Hessian = M/h² on the diagonal.
    const MatrixXd H = MatrixXd(energy.hessian(x, false));
    for (int i = 0; i < kVertices; ++i) EXPECT_NEAR(H(3 * i + 1, 3 * i + 1), masses[i] / (kDt * kDt), 1e-9);
}

TEST(InertiaEnergy, SetPreviousFormsTheInertialTarget)
{
    Rng rng(83);
    InertiaEnergy energy(VectorXd::Ones(kVertices), kDt);
    const VectorXd x_prev = rng.uniform_vector(3 * kVertices, -1, 1);
    const VectorXd x_prev2 = rng.uniform_vector(3 * kVertices, -1, 1);
    energy.set_previous(x_prev, x_prev2);
    EXPECT_EQ(energy.x_tilde(), VectorXd(2.0 * x_prev - x_prev2));
    EXPECT_NEAR(energy.value(2.0 * x_prev - x_prev2), 0.0, 1e-30);
}

TEST(InertiaEnergy, RejectsWrongSizesAndNonPositiveStep)
{
    InertiaEnergy energy(VectorXd::Ones(kVertices), kDt);
    EXPECT_THROW(energy.set_x_tilde(VectorXd::Zero(kVertices)), Error);
    EXPECT_THROW(energy.set_previous(VectorXd::Zero(3 * kVertices), VectorXd::Zero(kVertices)), Error);
    EXPECT_THROW(InertiaEnergy(VectorXd::Ones(kVertices), 0.0), Error);
    EXPECT_THROW(InertiaEnergy(-VectorXd::Ones(kVertices), kDt), Error);
}

} // namespace
} // namespace lb
