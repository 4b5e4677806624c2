#pragma once
// Property checks shared by every energy test: they run the one generic derivative
// test (tests/support/finite_difference.hpp) on a whole-mesh Energy, plus rigid-motion
// invariance, element Hessian symmetry and PSD projection.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/rng.hpp"
#include "core/types.hpp"
#include "mesh/generators.hpp"
#include "energy/energy.hpp"
#include "support/finite_difference.hpp"

namespace lb::testing {

// ---- tolerances (named, with their reasoning) ---------------------------------------

/// Central-difference step, as a fraction of the mesh's typical edge length: small
/// enough that truncation error (∝ step²) is ~1e-12 relative, large enough that
/// round-off (∝ ε/step) stays ~1e-10 relative.
constexpr double kFdRelativeStep = 1e-6;
/// Relative tolerance per entry of the generic check.
constexpr double kFdTolerance = 1e-5;
/// Absolute floor of the comparison, as a fraction of the largest analytic entry:
/// entries that should be zero differ from their finite difference by round-off
/// ~1e-10 of the largest entry, below the allowed kFdFloorFraction · kFdTolerance = 1e-9.
constexpr double kFdFloorFraction = 1e-4;
/// Rigid-motion invariance: relative change of the energy value and gradient.
constexpr double kRigidTolerance = 1e-9;
/// Element Hessian symmetry: max |H − Hᵀ| relative to max |H|.
constexpr double kSymmetryTolerance = 1e-12;
/// Min eigenvalue of a projected element Hessian, relative to max |H| (DESIGN: ≥ −1e-9·scale).
constexpr double kPsdTolerance = 1e-9;

// ---- states ---------------------------------------------------------------------

/// x = rest + uniform noise in [−amplitude, amplitude] per coordinate (3N).
inline VectorXd perturbed_state(const MatrixX3d& rest, double amplitude, Rng& rng)
{
    return flatten(rest) + rng.uniform_vector(3 * rest.rows(), -amplitude, amplitude);
}

/// A uniformly random rotation (from a normalised random quaternion).
inline Matrix3d random_rotation(Rng& rng)
{
    Eigen::Quaterniond q(rng.normal(), rng.normal(), rng.normal(), rng.normal());
    q.normalize();
    return q.toRotationMatrix();
}

/// x ↦ (R x_i + t)_i for every vertex.
inline VectorXd rigidly_moved(const VectorXd& x, const Matrix3d& R, const Vector3d& t)
{
    VectorXd y(x.size());
    for (Index i = 0; i < x.size() / 3; ++i) y.segment<3>(3 * i) = R * x.segment<3>(3 * i) + t;
    return y;
}

// ---- checks ---------------------------------------------------------------------

inline FdOptions fd_options(double length_scale, const MatrixXd& analytic)
{
    FdOptions opt;
    opt.step = kFdRelativeStep * length_scale;
    opt.tol = kFdTolerance;
    opt.scale = std::max(kFdFloorFraction * analytic.cwiseAbs().maxCoeff(), 1e-300);
    return opt;
}

/// The fused pass (Energy::add_value_gradient, element_value_gradient overrides) against
/// value() and gradient(), serially and inside a parallel region, to round-off.
inline ::testing::AssertionResult check_fused_value_gradient(const Energy& energy, const VectorXd& x)
{
    const double value = energy.value(x);
    const VectorXd gradient = energy.gradient(x);
    for (bool nested : {false, true}) {
        VectorXd g = VectorXd::Constant(x.size(), 0.25);
        double fused = 0.0;
#pragma omp parallel num_threads(2) if (nested)
        {
#pragma omp single
            fused = energy.add_value_gradient(x, 2.0, g);
        }
        const double scale = std::max(gradient.cwiseAbs().maxCoeff(), 1e-300);
        const double value_error = std::abs(fused - value) / std::max(std::abs(value), 1e-300);
        const double gradient_error =
            (g - VectorXd::Constant(x.size(), 0.25) - 2.0 * gradient).cwiseAbs().maxCoeff() / (2.0 * scale);
        if (!(value_error < 1e-12 && gradient_error < 1e-12))
            return ::testing::AssertionFailure() << energy.name() << " add_value_gradient (" << (nested ? "nested" : "top level")
                                                 << "): value error " << value_error << ", gradient error "
                                                 << gradient_error << " relative";
    }
    return ::testing::AssertionSuccess();
}

/// ∇E against central differences of E (whole mesh), and the fused value-gradient pass
/// against both.
inline ::testing::AssertionResult check_energy_gradient(const Energy& energy, const VectorXd& x,
                                                        double length_scale)
{
    if (auto fused = check_fused_value_gradient(energy, x); !fused) return fused;
    const MatrixXd analytic = energy.gradient(x).transpose();
    return check_gradient([&](const VectorXd& y) { return energy.value(y); },
                          [&](const VectorXd& y) { return energy.gradient(y); }, x,
                          fd_options(length_scale, analytic), energy.name() + " gradient");
}

/// Unprojected ∇²E against the central-difference Jacobian of ∇E (whole mesh).
inline ::testing::AssertionResult check_energy_hessian(const Energy& energy, const VectorXd& x,
                                                       double length_scale)
{
    const MatrixXd analytic = MatrixXd(energy.hessian(x, /*project_psd=*/false));
    return check_jacobian([&](const VectorXd& y) { return energy.gradient(y); }, analytic, x,
                          fd_options(length_scale, analytic), energy.name() + " hessian");
}

/// E(Rx + t) = E(x) and ∇E(Rx + t) = R ∇E(x) vertexwise.
inline ::testing::AssertionResult check_rigid_invariance(const Energy& energy, const VectorXd& x, Rng& rng)
{
    const Matrix3d R = random_rotation(rng);
    const Vector3d t(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const VectorXd y = rigidly_moved(x, R, t);
    const double e0 = energy.value(x), e1 = energy.value(y);
    if (!(std::abs(e0 - e1) <= kRigidTolerance * std::max(std::abs(e0), 1e-300))) {
        return ::testing::AssertionFailure() << energy.name() << ": energy changed under a rigid motion: "
                                             << e0 << " -> " << e1;
    }
    const VectorXd g0 = rigidly_moved(energy.gradient(x), R, Vector3d::Zero());
    const VectorXd g1 = energy.gradient(y);
    const double err = (g0 - g1).cwiseAbs().maxCoeff();
    const double ref = g0.cwiseAbs().maxCoeff();
    if (!(err <= kRigidTolerance * ref) || !(ref > 0.0)) {
        return ::testing::AssertionFailure() << energy.name()
                                             << ": gradient does not rotate with the state: max error "
                                             << err << " vs max entry " << ref;
    }
    return ::testing::AssertionSuccess();
}

/// The standard derivative test of an energy: check_energy_gradient and
/// check_energy_hessian at `trials` random perturbations of the rest state (amplitude
/// `perturbation`, m), with `length_scale` as the FD scale. Fails naming the trial.
inline ::testing::AssertionResult check_derivatives_near_rest(const Energy& energy, const MatrixX3d& rest,
                                                              double perturbation, double length_scale, Rng& rng,
                                                              int trials = 3)
{
    for (int trial = 0; trial < trials; ++trial) {
        const VectorXd x = perturbed_state(rest, perturbation, rng);
        for (const auto& result : {check_energy_gradient(energy, x, length_scale), check_energy_hessian(energy, x, length_scale)}) {
            if (!result) return ::testing::AssertionFailure() << "trial " << trial << ": " << result.message();
        }
    }
    return ::testing::AssertionSuccess();
}

/// check_rigid_invariance at `trials` random perturbations of the rest state.
inline ::testing::AssertionResult check_rigid_invariance_near_rest(const Energy& energy, const MatrixX3d& rest,
                                                                   double perturbation, Rng& rng, int trials = 3)
{
    for (int trial = 0; trial < trials; ++trial) {
        const auto result = check_rigid_invariance(energy, perturbed_state(rest, perturbation, rng), rng);
        if (!result) return ::testing::AssertionFailure() << "trial " << trial << ": " << result.message();
    }
    return ::testing::AssertionSuccess();
}

/// Every element Hessian is symmetric, and after projection its smallest eigenvalue is
/// ≥ −kPsdTolerance·max|H|. Also reports how many elements were indefinite before
/// projection (so a test can assert the projection was exercised).
inline ::testing::AssertionResult check_element_hessians(const Energy& energy, const VectorXd& x,
                                                         Index* num_indefinite = nullptr)
{
    const int dofs = 3 * energy.nodes_per_element();
    MatrixXd H(dofs, dofs), P(dofs, dofs);
    Index indefinite = 0;
    for (Index e = 0; e < energy.num_elements(); ++e) {
        energy.element_hessian(e, x, false, H.data());
        const double scale = H.cwiseAbs().maxCoeff();
        const double asym = (H - H.transpose()).cwiseAbs().maxCoeff();
        if (!(asym <= kSymmetryTolerance * scale)) {
            return ::testing::AssertionFailure() << energy.name() << ": element " << e
                                                 << " Hessian not symmetric: max |H - H^T| = " << asym
                                                 << ", max |H| = " << scale;
        }
        Eigen::SelfAdjointEigenSolver<MatrixXd> before(H, Eigen::EigenvaluesOnly);
        if (before.eigenvalues().minCoeff() < -kPsdTolerance * scale) ++indefinite;
        energy.element_hessian(e, x, true, P.data());
        Eigen::SelfAdjointEigenSolver<MatrixXd> after(0.5 * (P + P.transpose()), Eigen::EigenvaluesOnly);
        const double min_eig = after.eigenvalues().minCoeff();
        if (!(min_eig >= -kPsdTolerance * scale)) {
            return ::testing::AssertionFailure() << energy.name() << ": element " << e
                                                 << " projected Hessian has eigenvalue " << min_eig
                                                 << " (max |H| = " << scale << ")";
        }
    }
    if (num_indefinite != nullptr) *num_indefinite = indefinite;
    return ::testing::AssertionSuccess();
}

/// Mean edge length of the elements' vertex pairs: the length scale of FD steps.
inline double mean_element_edge(const Energy& energy, const MatrixX3d& rest)
{
    double sum = 0.0;
    long count = 0;
    const int k = energy.nodes_per_element();
    for (Index e = 0; e < energy.num_elements(); ++e) {
        const int* nodes = energy.element_nodes(e);
        for (int a = 0; a < k; ++a) {
            for (int b = a + 1; b < k; ++b) {
                sum += (rest.row(nodes[a]) - rest.row(nodes[b])).norm();
                ++count;
            }
        }
    }
    return count > 0 ? sum / double(count) : 1.0;
}

/// Small meshes shared by the energy tests (generated, z-up).
inline
Mesh small_bundle()
{
    RodBundleOptions options;
    options.num_rods_x = 2;
    options.num_rods_y = 2;
    options.vertices_per_rod = 6;
    options.length = 0.5;
    options.spacing = 0.1;
    return make_rod_bundle(options);
}

inline
Mesh small_cloth()
{
    ClothGridOptions options;
    options.nx = 5;
    options.ny = 4;
    options.width = 0.4;
    options.height = 0.3;
    return make_cloth_grid(options);
}

} // namespace lb::testing
