#include "energy/stvk_density.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <vector>

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

// ---- analytic eigensystem of ∂P/∂F and its projection ---------------------------

/// Reconstruction of ∂P/∂F from the analytic eigensystem, relative to max |∂P/∂F|:
/// only round-off of O(1) arithmetic on O(1) entries.
constexpr double kEigensystemTolerance = 1e-10;
/// Analytic clamp vs a 9×9 numerical eigen-clamp, relative to max |∂P/∂F| (the brief's bound).
constexpr double kProjectionTolerance = 1e-8;

/// Lamé pairs covering ν ≈ 0.3, nearly incompressible ν ≈ 0.48, and auxetic λ < 0.
const std::vector<LameParameters>& test_lame_parameters()
{
    static const std::vector<LameParameters> lames{{3.0, 5.0}, {1.0, 24.0}, {3.0, -1.5}};
    return lames;
}

Matrix3d random_rotation(Rng& rng)
{
    Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    q.normalize();
    return q.toRotationMatrix();
}

/// Deformation gradients that exercise every branch: moderate strain, compression,
/// arbitrary (often inverted) matrices, reflections, repeated and zero singular values.
std::vector<Matrix3d> test_deformation_gradients(std::uint64_t seed)
{
    Rng rng(seed);
    auto noise = [&](double amplitude) {
        return Matrix3d(Matrix3d::NullaryExpr([&] { return rng.uniform(-amplitude, amplitude); }));
    };
    std::vector<Matrix3d> Fs;
    for (int trial = 0; trial < 6; ++trial) {
        Fs.push_back(Matrix3d::Identity() + noise(0.3));       // moderate strain
        Fs.push_back(0.6 * Matrix3d::Identity() + noise(0.3)); // compressed
        Fs.push_back(noise(1.5));                              // arbitrary, often inverted
        Matrix3d mirrored = Matrix3d::Identity() + noise(0.3);
        mirrored.row(0) *= -1.0;                               // inverted: det F < 0
        Fs.push_back(random_rotation(rng) * mirrored);
    }
    const Matrix3d R = random_rotation(rng);
    Fs.push_back(R);                                               // rest, rotated: σ = (1, 1, 1)
    Fs.push_back(0.7 * R);                                         // triple singular value
    Fs.push_back(R * Eigen::Vector3d(1.2, 0.7, 0.7).asDiagonal()); // double singular value
    Fs.push_back(R * Eigen::Vector3d(1.1, 0.9, 0.0).asDiagonal()); // flattened to a plane
    Fs.push_back(R * Eigen::Vector3d(1.1, 0.9, -0.2).asDiagonal() * random_rotation(rng)); // inverted
    Fs.push_back(Matrix3d::Zero());                                // collapsed to a point
    return Fs;
}

/// The brute-force reference: Q max(Λ, 0) Qᵀ from a numerical 9×9 eigendecomposition.
Eigen::Matrix<double, 9, 9> numerically_clamped(const Eigen::Matrix<double, 9, 9>& M)
{
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eig(M);
    return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}

TEST(StvkDensity, AnalyticEigensystemReconstructsStressDerivative)
{
    int inverted = 0;
    for (const LameParameters& lame : test_lame_parameters()) {
        for (const Matrix3d& F : test_deformation_gradients(21)) {
            if (F.determinant() < 0.0) ++inverted;
            const StvkStressEigensystem es = stvk_stress_eigensystem(F, lame);
            const Eigen::Matrix<double, 9, 9> dPdF = stvk_dPdF<3>(F, lame);
            const double scale = std::max(dPdF.cwiseAbs().maxCoeff(), 1.0);
            EXPECT_LT((es.U * es.sigma.asDiagonal() * es.V.transpose() - F).cwiseAbs().maxCoeff(), 1e-12);

            Eigen::Matrix<double, 9, 9> modes, reconstructed = Eigen::Matrix<double, 9, 9>::Zero();
            for (int k = 0; k < StvkStressEigensystem::kModes; ++k) {
                const Matrix3d Q = es.mode(k);
                modes.col(k) = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(Q.data());
                reconstructed += es.value(k) * modes.col(k) * modes.col(k).transpose();
                // Each mode is an eigenvector on its own: (∂P/∂F) q_k = λ_k q_k.
                EXPECT_LT((dPdF * modes.col(k) - es.value(k) * modes.col(k)).cwiseAbs().maxCoeff(),
                          kEigensystemTolerance * scale)
                    << "mode " << k << " at F =\n" << F;
            }
            EXPECT_LT((modes.transpose() * modes - Eigen::Matrix<double, 9, 9>::Identity()).cwiseAbs().maxCoeff(),
                      1e-12);
            EXPECT_LT((reconstructed - dPdF).cwiseAbs().maxCoeff(), kEigensystemTolerance * scale) << "F =\n" << F;
        }
    }
    EXPECT_GT(inverted, 0) << "the test set should contain inverted deformation gradients";
}

TEST(StvkDensity, AnalyticProjectionMatchesNumericalEigenClamp)
{
    int indefinite = 0, definite = 0;
    for (const LameParameters& lame : test_lame_parameters()) {
        for (const Matrix3d& F : test_deformation_gradients(22)) {
            const Eigen::Matrix<double, 9, 9> dPdF = stvk_dPdF<3>(F, lame);
            const double scale = std::max(dPdF.cwiseAbs().maxCoeff(), 1.0);
            const Eigen::Matrix<double, 9, 9> reference = numerically_clamped(dPdF);
            const Eigen::Matrix<double, 9, 9> analytic = stvk_projected_dPdF(F, lame);
            EXPECT_LT((analytic - reference).cwiseAbs().maxCoeff(), kProjectionTolerance * scale)
                << "F =\n" << F << "\nmu = " << lame.mu << ", lambda = " << lame.lambda;
            const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>>(dPdF, Eigen::EigenvaluesOnly)
                                       .eigenvalues()
                                       .minCoeff();
            (min_eig < 0.0 ? indefinite : definite) += 1;
        }
    }
    EXPECT_GT(indefinite, 0);
    EXPECT_GT(definite, 0);
}

TEST(StvkDensity, PairEigenvaluesAtRestAreRotationsAndShears)
{
    // σ = 1: twists are the rotations (0), flips the pure shears (2μ), and A = 2μ I + λ 11ᵀ.
    const LameParameters lame{2.0, 7.0};
    const Eigen::Vector3d rest = Eigen::Vector3d::Ones();
    EXPECT_LT(stvk_pair_values(rest, lame, -1.0).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((stvk_pair_values(rest, lame, +1.0) - Eigen::Vector3d::Constant(2 * lame.mu)).cwiseAbs().maxCoeff(),
              1e-14);
    const Matrix3d expected = 2 * lame.mu * Matrix3d::Identity() + lame.lambda * Matrix3d::Ones();
    EXPECT_LT((stvk_scaling_block(rest, lame) - expected).cwiseAbs().maxCoeff(), 1e-14);
    // Uniform compression σ = s: twist μ s² + λ·3(s² − 1)/2 − μ < 0 for s < 1.
    EXPECT_LT(stvk_pair_values(Eigen::Vector3d::Constant(0.9), lame, -1.0).maxCoeff(), 0.0);
}

} // namespace
} // namespace lb
