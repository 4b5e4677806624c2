#include "energy/dihedral_angle.hpp"

#include <Eigen/Geometry>
#include <cmath>

#include "core/rng.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using testing::check_gradient;
using testing::check_jacobian;
using testing::FdOptions;

constexpr double kFdStep = 1e-6;  // hinge size O(1)
constexpr double kFdTolerance = 1e-5;
// Absolute floor: θ's derivatives are O(1) here and round-off in the differenced
// gradient is ~ε/step ≈ 1e-10, so entries that should vanish are compared to 1e-4·tol.
constexpr double kFdFloor = 1e-4;

// Flat hinge on the x axis: x0 = 0, x1 = e_x, x2 above (+y), x3 below, then x3 rotated
// about the edge by `fold` (radians).
HingeVector folded_hinge(double fold)
{
    const Vector3d x3 = Eigen::AngleAxisd(fold, Vector3d::UnitX()) * Vector3d(0.4, -0.7, 0.0);
    HingeVector xe;
    xe << 0, 0, 0, 1, 0, 0, 0.3, 0.8, 0, x3;
    return xe;
}

TEST(DihedralAngle, FlatIsZeroAndFoldsGiveTheFoldAngleWithSign)
{
    EXPECT_NEAR(dihedral_angle(folded_hinge(0.0)), 0.0, 1e-15);
    for (double fold : {0.1, 0.5, 1.0, 2.0, 3.0}) {
        EXPECT_NEAR(std::abs(dihedral_angle(folded_hinge(fold))), fold, 1e-12);
        EXPECT_NEAR(dihedral_angle(folded_hinge(fold)), -dihedral_angle(folded_hinge(-fold)), 1e-12);
    }
    // Sign convention: θ = atan2((n1×n2)·ê, n1·n2) with n1 ∝ (x1−x0)×(x2−x0), n2 ∝ (x3−x0)×(x1−x0).
    const HingeVector xe = folded_hinge(0.4);
    const Vector3d e = xe.segment<3>(3) - xe.segment<3>(0);
    const Vector3d n1 = e.cross(xe.segment<3>(6)).normalized();
    const Vector3d n2 = xe.segment<3>(9).cross(e).normalized();
    EXPECT_NEAR(dihedral_angle(xe), std::atan2(n1.cross(n2).dot(e.normalized()), n1.dot(n2)), 1e-14);
}

TEST(DihedralAngle, GradientAndHessianMatchFiniteDifferences)
{
    Rng rng(23);
    FdOptions opt;
    opt.step = kFdStep;
    opt.tol = kFdTolerance;
    opt.scale = kFdFloor;
    for (int trial = 0; trial < 10; ++trial) {
        HingeVector xe = folded_hinge(rng.uniform(-2.5, 2.5));
        xe += HingeVector::NullaryExpr([&] { return rng.uniform(-0.2, 0.2); });
        auto grad = [](const VectorXd& y) {
            HingeVector g;
            dihedral_angle(HingeVector(y), &g, nullptr);
            return VectorXd(g);
        };
        HingeVector g;
        HingeMatrix H;
        dihedral_angle(xe, &g, &H);
        EXPECT_TRUE(check_gradient([](const VectorXd& y) { return dihedral_angle(HingeVector(y)); }, grad, xe,
                                   opt, "dtheta/dx"))
            << "trial " << trial;
        EXPECT_TRUE(check_jacobian(grad, MatrixXd(H), xe, opt, "d2theta/dx2")) << "trial " << trial;
        EXPECT_LT((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
        // θ is invariant to translations: gradient sums to zero over the four vertices.
        EXPECT_LT((g.segment<3>(0) + g.segment<3>(3) + g.segment<3>(6) + g.segment<3>(9)).norm(), 1e-12);
    }
}

TEST(DihedralAngle, GradientRouteEqualsTheHessianRoutesGradient)
{
    // dihedral_angle has two routes: the normals' closed form when only θ and ∇θ are asked
    // for (the training losses' pass) and the (e, u, v) route with the Hessian. They must
    // give one θ and one ∇θ, to round-off, including near-flat and near-folded hinges.
    Rng rng(29);
    for (double fold : {0.0, 1e-7, 0.3, -1.2, 2.9, -3.1}) {
        for (int trial = 0; trial < 5; ++trial) {
            HingeVector xe = folded_hinge(fold);
            xe += HingeVector::NullaryExpr([&] { return rng.uniform(-0.2, 0.2); });
            HingeVector g_fast, g_full;
            HingeMatrix H;
            const double theta_fast = dihedral_angle(xe, &g_fast, nullptr);
            const double theta_full = dihedral_angle(xe, &g_full, &H);
            EXPECT_NEAR(theta_fast, theta_full, 1e-14) << "fold " << fold;
            EXPECT_NEAR(theta_fast, dihedral_angle(xe), 0.0) << "fold " << fold;
            EXPECT_LT((g_fast - g_full).norm(), 1e-13 * g_full.norm()) << "fold " << fold << ", trial " << trial;
        }
    }
}

TEST(DihedralAngle, WrapAngleMapsIntoHalfOpenInterval)
{
    EXPECT_NEAR(wrap_angle(0.3), 0.3, 1e-15);
    EXPECT_NEAR(wrap_angle(0.3 + 2 * M_PI), 0.3, 1e-14);
    EXPECT_NEAR(wrap_angle(-0.3 - 4 * M_PI), -0.3, 1e-14);
    EXPECT_NEAR(wrap_angle(3 * M_PI / 2), -M_PI / 2, 1e-14);
    EXPECT_NEAR(wrap_angle(-M_PI), M_PI, 1e-14);
    // Below 2π in magnitude (a difference of two angles in (−π, π]) it only adds or
    // subtracts one turn.
    EXPECT_EQ(wrap_angle(M_PI + 0.25), M_PI + 0.25 - 2 * M_PI);
    EXPECT_EQ(wrap_angle(-M_PI - 0.25), -M_PI - 0.25 + 2 * M_PI);
    EXPECT_EQ(wrap_angle(M_PI), M_PI);
}

} // namespace
} // namespace lb
