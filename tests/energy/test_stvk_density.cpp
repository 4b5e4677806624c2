#include "energy/stvk_density.hpp"

#include <Eigen/Geometry>

#include "core/rng.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using testing::check_gradient;
using testing::check_jacobian;
using testing::FdOptions;

constexpr double kFdStep = 1e-6;   // F is dimensionless, entries O(1)
constexpr double kFdTolerance = 1e-6;

template <int D>
void check_density_derivatives(std::uint64_t seed)
{
    const LameParameters lame{3.0, 5.0};
    Rng rng(seed);
    DeformationGradient<D> F0 = DeformationGradient<D>::Identity();
    F0 += DeformationGradient<D>::NullaryExpr([&] { return rng.uniform(-0.4, 0.4); });
    const VectorXd f0 = Eigen::Map<const VectorXd>(F0.data(), 3 * D);
    auto as_F = [](const VectorXd& f) { return DeformationGradient<D>(Eigen::Map<const DeformationGradient<D>>(f.data())); };
    auto P_of = [&](const VectorXd& f) {
        const DeformationGradient<D> P = stvk_first_piola<D>(as_F(f), lame);
        return VectorXd(Eigen::Map<const VectorXd>(P.data(), 3 * D));
    };
    FdOptions opt;
    opt.step = kFdStep;
    opt.tol = kFdTolerance;
    EXPECT_TRUE(check_gradient([&](const VectorXd& f) { return stvk_psi<D>(as_F(f), lame); }, P_of, f0, opt,
                               "P = dpsi/dF"));
    EXPECT_TRUE(check_jacobian(P_of, MatrixXd(stvk_dPdF<D>(F0, lame)), f0, opt, "dP/dF"));
}

TEST(StvkDensity, FirstPiolaAndItsDerivativeMatchFiniteDifferences3D)
{
    for (std::uint64_t seed : {1u, 2u, 3u}) check_density_derivatives<3>(seed);
}

TEST(StvkDensity, FirstPiolaAndItsDerivativeMatchFiniteDifferences2D)
{
    for (std::uint64_t seed : {4u, 5u, 6u}) check_density_derivatives<2>(seed);
}

TEST(StvkDensity, VanishesAtRotationsAndMatchesUniaxialStrain)
{
    const LameParameters lame{2.0, 7.0};
    const Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    EXPECT_NEAR(stvk_psi<3>(R, lame), 0.0, 1e-24);
    EXPECT_LT(stvk_first_piola<3>(R, lame).cwiseAbs().maxCoeff(), 1e-14);
    Matrix3d F = Matrix3d::Identity();
    F(0, 0) = 1.3;
    const double g = 0.5 * (1.3 * 1.3 - 1.0);
    EXPECT_NEAR(stvk_psi<3>(F, lame), lame.mu * g * g + 0.5 * lame.lambda * g * g, 1e-14);
}

TEST(StvkDensity, PlaneStressParametersReproduceShellModulus)
{
    // μ||G||² + ½λ_ps(tr G)² = k/(2t)·[(1−ν)||G||² + ν(tr G)²] with k = E t/(1−ν²).
    const double E = 2e5, nu = 0.3;
    const LameParameters ps = plane_stress_lame_parameters(E, nu);
    Eigen::Matrix<double, 3, 2> F;
    F << 1.2, 0.1, -0.05, 0.9, 0.2, 0.1;
    const Eigen::Matrix2d G = green_strain<2>(F);
    const double k_over_t = E / (1 - nu * nu);
    const double expected = 0.5 * k_over_t * ((1 - nu) * G.squaredNorm() + nu * G.trace() * G.trace());
    EXPECT_NEAR(stvk_psi<2>(F, ps), expected, 1e-12 * expected);
}

} // namespace
} // namespace lb
