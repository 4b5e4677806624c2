#include "energy/rod_curvature.hpp"

#include <cmath>

#include "core/rng.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using testing::check_jacobian;
using testing::fd_jacobian;
using testing::FdOptions;

constexpr double kFdStep = 1e-6;  // edges O(1)
constexpr double kFdTolerance = 1e-5;
// Absolute floor: derivatives are O(1) here, round-off of the differences ~ε/step ≈ 1e-10.
constexpr double kFdFloor = 1e-4;

Vector3d random_vector(Rng& rng) { return {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)}; }

TEST(RodCurvature, MagnitudeIsTwiceTanOfHalfTurningAngle)
{
    for (double phi : {0.0, 0.1, 1.0, 2.5}) {
        const Vector3d e0(1.0, 0.0, 0.0);
        const Vector3d e1 = 0.7 * Vector3d(std::cos(phi), std::sin(phi), 0.0);
        const Vector3d kb = curvature_binormal(e0, e1);
        EXPECT_NEAR(kb.norm(), 2 * std::tan(phi / 2), 1e-12);
        EXPECT_NEAR(kb.x(), 0.0, 1e-15);
        EXPECT_GE(kb.z(), 0.0);
    }
}

TEST(RodCurvature, JacobianAndContractedHessianMatchFiniteDifferences)
{
    Rng rng(59);
    FdOptions opt;
    opt.step = kFdStep;
    opt.tol = kFdTolerance;
    opt.scale = kFdFloor;
    for (int trial = 0; trial < 10; ++trial) {
        const Vector3d e0 = random_vector(rng).normalized() * rng.uniform(0.5, 1.5);
        // Turning angles up to ~120°, away from the fold-back singularity.
        const Vector3d e1 = (e0.normalized() + 1.5 * random_vector(rng)).normalized() * rng.uniform(0.5, 1.5);
        if (e0.normalized().dot(e1.normalized()) < -0.5) continue;
        const Vector3d w = random_vector(rng);
        Eigen::Matrix<double, 6, 1> z;
        z << e0, e1;

        auto kb_of = [](const VectorXd& y) {
            return VectorXd(curvature_binormal(y.head<3>(), y.tail<3>()));
        };
        Matrix36d J;
        curvature_binormal(e0, e1, &J);
        EXPECT_TRUE(check_jacobian(kb_of, MatrixXd(J), z, opt, "dkb/dz")) << "trial " << trial;

        // Σ_k w_k ∇²κb_k is the Jacobian of Jᵀw.
        auto Jt_w = [&](const VectorXd& y) {
            Matrix36d Jy;
            curvature_binormal(y.head<3>(), y.tail<3>(), &Jy);
            return VectorXd(Jy.transpose() * w);
        };
        // The vector-Jacobian product without J is Jᵀw.
        // The vector-Jacobian product without J (w = s κb) is Jᵀw, and returns κb and |κb|².
        const Vector3d kb = curvature_binormal(e0, e1);
        const double s = 0.5 + trial;
        double a0[3], a1[3], kb_out[3], vjp[6];
        for (int i = 0; i < 3; ++i) a0[i] = e0[i], a1[i] = e1[i];
        const double kk = curvature_binormal_vjp(a0, a1, s, kb_out, vjp);
        EXPECT_LT((Eigen::Map<const Eigen::Matrix<double, 6, 1>>(vjp) - J.transpose() * (s * kb)).norm(),
                  1e-14 * (J.norm() * s * kb.norm()))
            << "trial " << trial;
        EXPECT_LT((Eigen::Map<const Vector3d>(kb_out) - kb).norm(), 1e-14 * kb.norm()) << "trial " << trial;
        EXPECT_NEAR(kk, kb.squaredNorm(), 1e-14 * kb.squaredNorm()) << "trial " << trial;
        const Matrix6d H = curvature_binormal_contracted_hessian(e0, e1, w);
        EXPECT_TRUE(check_jacobian(Jt_w, MatrixXd(H), z, opt, "w . d2kb/dz2")) << "trial " << trial;
        EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
    }
}

} // namespace
} // namespace lb
