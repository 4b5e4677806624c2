// BC-relative encodings: exact round trips, what is excluded / re-applied, and the
// chain rule of gradient_to_features against finite differences.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "latent/bc_encoding.hpp"
#include "latent/latent_test_support.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using latent_test::random_matrix;
using latent_test::targets_of;

/// Random deformed frames: rest positions + noise of `amplitude` (m), 3N × S.
MatrixXd random_frames(const PhysicsSpec& p, Index S, Rng& rng, double amplitude = 0.1)
{
    const VectorXd rest = flatten(p.mesh.rest_positions);
    return random_matrix(rest.size(), S, rng, -amplitude, amplitude).colwise() + rest;
}

struct Case {
    const char* name;
    PhysicsSpec (*physics)();
    bool rods;
    EncodingFrame frame = EncodingFrame::translation;
};

/// Q x + t for every vertex of every column.
MatrixXd moved_rigidly(const MatrixXd& X, const Matrix3d& Q, const Vector3d& t)
{
    MatrixXd Y(X.rows(), X.cols());
    for (Index s = 0; s < X.cols(); ++s)
        for (Index i = 0; i < X.rows() / 3; ++i) Y.col(s).segment<3>(3 * i) = Q * X.col(s).segment<3>(3 * i) + t;
    return Y;
}

class EncodingCase : public ::testing::TestWithParam<Case> { };

TEST_P(EncodingCase, RoundTripIsExact)
{
    const PhysicsSpec p = GetParam().physics();
    const BcRelativeEncoding enc(p, GetParam().frame);
    const Index N = p.mesh.num_vertices(), B = Index(p.bc_indices.size());
    EXPECT_EQ(enc.rod_relative(), GetParam().rods);
    EXPECT_EQ(enc.num_dofs(), 3 * N);
    EXPECT_EQ(enc.num_features(), GetParam().rods ? 3 * (N - Index(p.mesh.rods.size())) : 3 * N);

    Rng rng(1);
    const MatrixXd X = random_frames(p, 5, rng);
    const MatrixXd F = enc.to_features(X);
    ASSERT_EQ(F.rows(), enc.num_features());
    ASSERT_EQ(F.cols(), 5);
    const MatrixXd X_back = enc.to_positions(F, targets_of(X, p.bc_indices));
    EXPECT_LE((X_back - X).cwiseAbs().maxCoeff(), 1e-14) << "to_positions(to_features(x), targets of x) != x";
    (void)B;
}

TEST_P(EncodingCase, FeaturesAreTranslationInvariant)
{
    // Relative to the boundary: a rigid translation of everything changes no feature.
    const PhysicsSpec p = GetParam().physics();
    const BcRelativeEncoding enc(p, GetParam().frame);
    Rng rng(2);
    const MatrixXd X = random_frames(p, 3, rng);
    MatrixXd X_shifted = X;
    const Vector3d shift(0.7, -1.3, 2.1);
    for (Index i = 0; i < X.rows() / 3; ++i) X_shifted.middleRows<3>(3 * i).colwise() += shift;
    EXPECT_LE((enc.to_features(X_shifted) - enc.to_features(X)).cwiseAbs().maxCoeff(), 1e-14);
}

TEST_P(EncodingCase, GradientToFeaturesMatchesFiniteDifferences)
{
    // L(f) = φ(to_positions(f, targets)), φ(x) = Σ_i w_i sin(x_i) + ½ c_i x_i²:
    // ∂L/∂f = gradient_to_features(∇φ(x), targets).
    const PhysicsSpec p = GetParam().physics();
    const BcRelativeEncoding enc(p, GetParam().frame);
    Rng rng(3);
    const MatrixXd X = random_frames(p, 1, rng);
    const MatrixXd T = targets_of(X, p.bc_indices) + random_matrix(3 * Index(p.bc_indices.size()), 1, rng, -0.05, 0.05);
    const VectorXd w = random_matrix(enc.num_dofs(), 1, rng);
    const VectorXd c = random_matrix(enc.num_dofs(), 1, rng, 0.5, 2.0);
    auto phi = [&](const VectorXd& x) { return (w.array() * x.array().sin() + 0.5 * c.array() * x.array().square()).sum(); };
    auto grad_phi = [&](const VectorXd& x) -> VectorXd { return w.array() * x.array().cos() + c.array() * x.array(); };
    const VectorXd f0 = enc.to_features(X).col(0);
    EXPECT_TRUE(lb::testing::check_gradient(
        [&](const VectorXd& f) { return phi(enc.to_positions(f, T).col(0)); },
        [&](const VectorXd& f) -> VectorXd { return enc.gradient_to_features(grad_phi(enc.to_positions(f, T).col(0)), T); },
        f0, {}, std::string(GetParam().name) + ": gradient_to_features"));
}

// The rigid frame moves the whole state into the boundary's best-fit frame: a rotation
// of the boundary together with the body it carries changes no feature (the translation
// frame's features rotate with it), and decoding at rotated targets rotates the result.
TEST_P(EncodingCase, RigidFrameFeaturesAreRotationInvariant)
{
    const PhysicsSpec p = GetParam().physics();
    const BcRelativeEncoding enc(p, GetParam().frame);
    Rng rng(6);
    const MatrixXd X = random_frames(p, 2, rng, 0.02);
    const Matrix3d Q = (Eigen::AngleAxisd(2.5, Vector3d(0.3, -1.0, 0.4).normalized()) *
                        Eigen::AngleAxisd(0.7, Vector3d::UnitZ())).toRotationMatrix();
    const Vector3d t(0.4, -0.2, 1.1);
    const MatrixXd moved = moved_rigidly(X, Q, t);
    const double change = (enc.to_features(moved) - enc.to_features(X)).cwiseAbs().maxCoeff();
    if (GetParam().frame == EncodingFrame::rigid) {
        EXPECT_LE(change, 1e-12);
        const MatrixXd F = random_matrix(enc.num_features(), 2, rng, -0.1, 0.1);
        const MatrixXd T = targets_of(X, p.bc_indices);
        EXPECT_LE((enc.to_positions(F, targets_of(moved, p.bc_indices)) - moved_rigidly(enc.to_positions(F, T), Q, t))
                      .cwiseAbs()
                      .maxCoeff(),
                  1e-12);
    } else {
        EXPECT_GT(change, 1e-3) << "the translation frame's features turn with the boundary";
    }
}

INSTANTIATE_TEST_SUITE_P(Physics, EncodingCase,
                         ::testing::Values(Case{"rods", latent_test::rod_physics, true},
                                           Case{"cloth", latent_test::cloth_physics, false},
                                           Case{"solid", latent_test::solid_physics, false},
                                           Case{"rods_rigid", latent_test::rod_physics, true, EncodingFrame::rigid},
                                           Case{"solid_rigid", latent_test::solid_physics, false, EncodingFrame::rigid}),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(BcEncoding, RodRootsAreExcludedAndReapplied)
{
    const PhysicsSpec p = latent_test::rod_physics();
    const BcRelativeEncoding enc(p);
    Rng rng(4);
    const MatrixXd X = random_frames(p, 2, rng);
    MatrixXd F = enc.to_features(X);
    // Feature k: the k-th non-root vertex (ascending order) relative to its root.
    const auto& rod = p.mesh.rods[1];
    const Index first_of_rod1 = Index(p.mesh.rods[0].size()) - 1;  // rod 0 contributes |rod| − 1 vertices first
    EXPECT_LE((F.col(0).segment<3>(3 * first_of_rod1) -
               (X.col(0).segment<3>(3 * rod[1]) - X.col(0).segment<3>(3 * rod[0]))).norm(), 1e-15);

    // Decoding puts roots exactly at their targets whatever the features, and every
    // other vertex at its root's target + its feature.
    F = random_matrix(F.rows(), F.cols(), rng);
    const MatrixXd T = random_matrix(3 * Index(p.bc_indices.size()), 2, rng);
    const MatrixXd Y = enc.to_positions(F, T);
    for (std::size_t r = 0; r < p.mesh.rods.size(); ++r) {
        EXPECT_EQ(Y.col(1).segment<3>(3 * p.mesh.rods[r][0]), T.col(1).segment<3>(3 * Index(r)));
    }
    EXPECT_LE((Y.col(1).segment<3>(3 * rod[1]) - (T.col(1).segment<3>(3) + F.col(1).segment<3>(3 * first_of_rod1))).norm(),
              1e-15);
    // The roots' gradient does not reach the features (they are fixed by the boundary).
    MatrixXd G = MatrixXd::Zero(enc.num_dofs(), 1);
    for (int b : p.bc_indices) G.col(0).segment<3>(3 * b).setOnes();
    EXPECT_EQ(enc.gradient_to_features(G, T.leftCols(1)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(BcEncoding, ClothDecodingAddsTheTargetMean)
{
    const PhysicsSpec p = latent_test::cloth_physics();
    const BcRelativeEncoding enc(p);
    Rng rng(5);
    const MatrixXd F = random_matrix(enc.num_features(), 1, rng);
    const MatrixXd T = random_matrix(6, 1, rng);
    const Vector3d mean = 0.5 * (T.col(0).segment<3>(0) + T.col(0).segment<3>(3));
    const MatrixXd X = enc.to_positions(F, T);
    for (Index i = 0; i < p.mesh.num_vertices(); ++i)
        EXPECT_LE((X.col(0).segment<3>(3 * i) - F.col(0).segment<3>(3 * i) - mean).norm(), 1e-15);
}

TEST(BcEncoding, RejectsRodsWhoseRootIsNotDirichlet)
{
    PhysicsSpec p = latent_test::rod_physics();
    p.bc_indices.erase(p.bc_indices.begin());
    EXPECT_THROW(BcRelativeEncoding{p}, ConfigError);
    p.bc_indices.clear();
    EXPECT_THROW(BcRelativeEncoding{p}, ConfigError);
}

TEST(BcEncoding, RigidFrameNeedsADirichletSetThatFixesARotation)
{
    // The small cloth's two pinned corners are collinear: a rotation about their line is free.
    const PhysicsSpec cloth = latent_test::cloth_physics();
    EXPECT_THROW(BcRelativeEncoding(cloth, EncodingFrame::rigid), ConfigError);
    EXPECT_NO_THROW(BcRelativeEncoding(cloth, EncodingFrame::translation));
    EXPECT_STREQ(BcRelativeEncoding(latent_test::solid_physics(), EncodingFrame::rigid).kind_name(), "dirichlet_rigid");
    EXPECT_STREQ(BcRelativeEncoding(latent_test::rod_physics(), EncodingFrame::rigid).kind_name(), "rod_root_rigid");
    EXPECT_EQ(parse_encoding_frame("rigid"), EncodingFrame::rigid);
    EXPECT_THROW(parse_encoding_frame("rotation"), ConfigError);
}

TEST(BcEncoding, RejectsWrongShapes)
{
    const PhysicsSpec p = latent_test::cloth_physics();
    const BcRelativeEncoding enc(p);
    EXPECT_THROW(enc.to_features(MatrixXd::Zero(enc.num_dofs() + 3, 1)), std::invalid_argument);
    EXPECT_THROW(enc.to_positions(MatrixXd::Zero(enc.num_features(), 2), MatrixXd::Zero(6, 1)), std::invalid_argument);
}

} // namespace
} // namespace lb
