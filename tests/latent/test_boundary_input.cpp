// BoundaryInput: p_t with the velocities only (the paper's, unchanged) or with the Dirichlet
// targets' rigid pose appended: the pose recovers a prescribed rotation and translation, is
// the identity at rest, and keeps R = I for a collinear Dirichlet set; bad input is refused.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "core/error.hpp"
#include "latent/boundary_input.hpp"
#include "latent/latent_test_support.hpp"

namespace lb {
namespace {

/// The rest Dirichlet positions of `physics` moved by x ↦ R x + t (3B).
VectorXd moved_targets(const PhysicsSpec& physics, const Matrix3d& R, const Vector3d& t)
{
    VectorXd x(3 * Index(physics.bc_indices.size()));
    for (size_t b = 0; b < physics.bc_indices.size(); ++b)
        x.segment<3>(3 * Index(b)) = R * physics.mesh.rest_positions.row(physics.bc_indices[b]).transpose() + t;
    return x;
}

TEST(BoundaryInput, VelocityIsTheScenesParametersUnchanged)
{
    const PhysicsSpec physics = latent_test::solid_physics();
    const BoundaryInput velocity(BoundaryInputKind::Velocity, physics);
    const VectorXd params = (VectorXd(6) << 0.1, -0.2, 0.3, 1.0, 2.0, 3.0).finished();
    EXPECT_EQ(velocity.size(6), 6);
    EXPECT_EQ(velocity.of_frame(params, moved_targets(physics, Matrix3d::Identity(), Vector3d::Ones())), params);
    EXPECT_EQ(BoundaryInput().kind(), BoundaryInputKind::Velocity);
}

TEST(BoundaryInput, PoseRecoversTheTargetsRigidMotion)
{
    const PhysicsSpec physics = latent_test::solid_physics();  // a face of the beam: not collinear
    const BoundaryInput pose(BoundaryInputKind::Pose, physics);
    const VectorXd params = VectorXd::LinSpaced(6, 1.0, 6.0);
    EXPECT_EQ(pose.size(6), 6 + BoundaryInput::kPoseSize);

    const VectorXd rest = moved_targets(physics, Matrix3d::Identity(), Vector3d::Zero());
    const Vector3d rest_centroid = as_rows(rest).colwise().mean().transpose();
    const VectorXd at_rest = pose.of_frame(params, rest);
    ASSERT_EQ(at_rest.size(), 15);
    EXPECT_EQ(at_rest.head(6), params);
    EXPECT_TRUE(at_rest.segment<3>(6).isApprox(rest_centroid, 1e-12));
    EXPECT_TRUE(at_rest.segment<3>(9).isApprox(Vector3d::UnitX(), 1e-12)) << at_rest.transpose();
    EXPECT_TRUE(at_rest.segment<3>(12).isApprox(Vector3d::UnitY(), 1e-12)) << at_rest.transpose();

    const Matrix3d R = Eigen::AngleAxisd(0.7, Vector3d(1.0, 2.0, 3.0).normalized()).toRotationMatrix();
    const Vector3d t(0.3, -0.1, 0.25);
    const VectorXd moved = pose.pose(moved_targets(physics, R, t));
    EXPECT_LT((moved.head<3>() - (R * rest_centroid + t)).norm(), 1e-12);
    EXPECT_LT((moved.segment<3>(3) - R.col(0)).norm(), 1e-12) << moved.transpose();
    EXPECT_LT((moved.segment<3>(6) - R.col(1)).norm(), 1e-12) << moved.transpose();
}

TEST(BoundaryInput, CollinearDirichletSetsKeepTheIdentityRotation)
{
    const PhysicsSpec physics = latent_test::cloth_physics();  // two corners
    ASSERT_EQ(physics.bc_indices.size(), 2u);
    const BoundaryInput pose(BoundaryInputKind::Pose, physics);
    const Matrix3d R = Eigen::AngleAxisd(0.5, Vector3d::UnitZ()).toRotationMatrix();
    const VectorXd targets = moved_targets(physics, R, Vector3d(0.0, 0.0, 1.0));
    const VectorXd p = pose.pose(targets);
    EXPECT_EQ(p.segment<3>(3), Vector3d::UnitX());
    EXPECT_EQ(p.segment<3>(6), Vector3d::UnitY());
    EXPECT_TRUE(p.head<3>().isApprox(as_rows(targets).colwise().mean().transpose(), 1e-12));
}

TEST(BoundaryInput, BadInputIsRefused)
{
    const PhysicsSpec physics = latent_test::solid_physics();
    const BoundaryInput pose(BoundaryInputKind::Pose, physics);
    EXPECT_THROW(pose.pose(VectorXd::Zero(3)), Error);
    EXPECT_THROW(BoundaryInput(BoundaryInputKind::Pose, VectorXd::Zero(4)), Error);
    EXPECT_EQ(boundary_input_from_string("pose"), BoundaryInputKind::Pose);
    EXPECT_EQ(boundary_input_from_string(to_string(BoundaryInputKind::Velocity)), BoundaryInputKind::Velocity);
    EXPECT_THROW(boundary_input_from_string("position"), ConfigError);
}

} // namespace
} // namespace lb
