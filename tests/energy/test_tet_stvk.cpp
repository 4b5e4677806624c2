#include "energy/tet_stvk.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <vector>

#include "core/error.hpp"
#include "energy_checks.hpp"
#include "mesh/generators.hpp"

namespace lb {
namespace {

using testing::check_derivatives_near_rest;
using testing::check_element_hessians;
using testing::check_rigid_invariance_near_rest;
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
    EXPECT_TRUE(check_derivatives_near_rest(energy, mesh.rest_positions, 0.3 * kCell, kCell, rng));
}

TEST(TetStVK, InvariantUnderRigidMotion)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(11);
    EXPECT_TRUE(check_rigid_invariance_near_rest(energy, mesh.rest_positions, 0.2 * kCell, rng));
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

// ---- the analytic PSD projection (local_projected_hessian) -------------------------

/// Projected vs exact element Hessian, and vs the brute-force V Jᵀ (∂P/∂F)₊ J, relative to
/// max |exact element Hessian|.
constexpr double kExactMatchTolerance = 1e-9;
constexpr double kBruteForceTolerance = 1e-8;
/// An eigenvalue of ∂P/∂F below −kClearlyNegative·max|∂P/∂F| must visibly change the Hessian.
constexpr double kClearlyNegative = 1e-3;

using ElementMatrix = TetStVK::ElementMatrix;

/// States of the small beam that make many elements indefinite: moderate noise, strong
/// compression, a mirror image (every tet inverted) and large noise (some inverted).
std::vector<VectorXd> hard_states(const Mesh& mesh, Rng& rng)
{
    std::vector<VectorXd> states;
    states.push_back(perturbed_state(mesh.rest_positions, 0.3 * kCell, rng));
    VectorXd compressed = 0.6 * flatten(mesh.rest_positions);
    compressed += rng.uniform_vector(compressed.size(), -0.1 * kCell, 0.1 * kCell);
    states.push_back(compressed);
    MatrixX3d mirrored = mesh.rest_positions;
    mirrored.col(0) *= -1.0;
    states.push_back(perturbed_state(mirrored, 0.1 * kCell, rng));
    states.push_back(perturbed_state(mesh.rest_positions, 1.0 * kCell, rng));
    return states;
}

ElementMatrix element_hessian(const TetStVK& energy, Index t, const VectorXd& x, bool project)
{
    ElementMatrix H;
    energy.element_hessian(t, x, project, H.data());
    return H;
}

/// J = ∂vec(F)/∂x_e (9×12): ∂F_ij/∂x_{a,k} = δ_ik b_a(j).
Eigen::Matrix<double, 9, 12> deformation_jacobian(const TetStVK::ShapeGradients& B)
{
    Eigen::Matrix<double, 9, 12> J = Eigen::Matrix<double, 9, 12>::Zero();
    for (int a = 0; a < 4; ++a) {
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) J(i + 3 * j, 3 * a + i) = B(a, j);
        }
    }
    return J;
}

double min_eigenvalue(const Eigen::Matrix<double, 9, 9>& M)
{
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>>(M, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
}

TEST(TetStVK, ProjectedHessiansSymmetricAndPsdIncludingInvertedStates)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(17);
    Index indefinite = 0, inverted = 0;
    for (const VectorXd& x : hard_states(mesh, rng)) {
        Index state_indefinite = 0;
        EXPECT_TRUE(check_element_hessians(energy, x, &state_indefinite));
        indefinite += state_indefinite;
        for (Index t = 0; t < energy.num_elements(); ++t) {
            if (energy.deformation_gradient(t, energy.gather(t, x)).determinant() < 0.0) ++inverted;
        }
    }
    EXPECT_GT(indefinite, 0);
    EXPECT_GT(inverted, 0) << "the states should invert some tets";
}

TEST(TetStVK, ProjectedHessianIsTheClampedStressDerivativePulledBack)
{
    // H₊ = V Jᵀ (∂P/∂F)₊ J with (∂P/∂F)₊ from a numerical 9×9 eigendecomposition.
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(19);
    for (const VectorXd& x : hard_states(mesh, rng)) {
        for (Index t = 0; t < energy.num_elements(); ++t) {
            const Matrix3d F = energy.deformation_gradient(t, energy.gather(t, x));
            const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> eig(stvk_dPdF<3>(F, energy.lame()));
            const Eigen::Matrix<double, 9, 9> clamped =
                eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
            const Eigen::Matrix<double, 9, 12> J = deformation_jacobian(energy.shape_gradients(t));
            const ElementMatrix reference = energy.rest_volume(t) * J.transpose() * clamped * J;
            const double scale = element_hessian(energy, t, x, false).cwiseAbs().maxCoeff();
            const double err = (element_hessian(energy, t, x, true) - reference).cwiseAbs().maxCoeff();
            ASSERT_LT(err, kBruteForceTolerance * scale) << "element " << t << ", F =\n" << F;
        }
    }
}

TEST(TetStVK, ProjectedHessianEqualsExactWhereExactIsPsd)
{
    const Mesh mesh = small_beam();
    const TetStVK energy(mesh.rest_positions, mesh.elements, kYoungs, kPoisson);
    Rng rng(23);
    // Small strains around a uniform stretch, around rest, and around a rotated rest state.
    MatrixX3d stretched = mesh.rest_positions;
    stretched *= 1.05;
    const Matrix3d R = testing::random_rotation(rng);
    const std::vector<VectorXd> states{
        perturbed_state(stretched, 0.01 * kCell, rng),
        perturbed_state(mesh.rest_positions, 0.02 * kCell, rng),
        testing::rigidly_moved(perturbed_state(mesh.rest_positions, 0.02 * kCell, rng), R, Vector3d(0.1, 0.2, 0.3)),
    };
    Index psd = 0, psd_without_positive_stress = 0, indefinite = 0;
    for (const VectorXd& x : states) {
        for (Index t = 0; t < energy.num_elements(); ++t) {
            const Matrix3d F = energy.deformation_gradient(t, energy.gather(t, x));
            const Eigen::Matrix<double, 9, 9> dPdF = stvk_dPdF<3>(F, energy.lame());
            const ElementMatrix exact = element_hessian(energy, t, x, false);
            const ElementMatrix projected = element_hessian(energy, t, x, true);
            const double err = (projected - exact).cwiseAbs().maxCoeff();
            const double scale = exact.cwiseAbs().maxCoeff();
            const double min_eig = min_eigenvalue(dPdF), dPdF_scale = dPdF.cwiseAbs().maxCoeff();
            if (min_eig > kExactMatchTolerance * dPdF_scale) {
                ++psd;
                // PSD states whose S is not positive definite take the SVD path.
                const Eigen::Vector3d s = Eigen::SelfAdjointEigenSolver<Matrix3d>(stvk_second_piola<3>(F, energy.lame()))
                                              .eigenvalues();
                if (s.minCoeff() <= 0.0) ++psd_without_positive_stress;
                EXPECT_LE(err, kExactMatchTolerance * scale) << "element " << t;
            } else if (min_eig < -kClearlyNegative * dPdF_scale) {
                ++indefinite;
                EXPECT_GT(err, kExactMatchTolerance * scale) << "an indefinite element Hessian must change";
            }
        }
    }
    EXPECT_GT(psd, 0);
    EXPECT_GT(psd_without_positive_stress, 0) << "no PSD element exercised the SVD path";
    EXPECT_GT(indefinite, 0);
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
