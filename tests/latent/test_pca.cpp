// PCA against an independent SVD (both Gram-matrix branches), exact reproduction of
// rank-deficient data, and Eckart–Young optimality of the truncation.
#include <gtest/gtest.h>

#include <Eigen/SVD>

#include "latent/latent_test_support.hpp"
#include "latent/pca.hpp"

namespace lb {
namespace {

using latent_test::random_matrix;

/// F × S data of exact rank r around a non-zero mean.
MatrixXd low_rank_data(Index F, Index S, Index r, Rng& rng)
{
    const MatrixXd A = random_matrix(F, r, rng);
    const MatrixXd B = random_matrix(r, S, rng);
    return (A * B).colwise() + random_matrix(F, 1, rng, 2.0, 3.0).col(0);
}

MatrixXd project(const PcaBasis& p, const MatrixXd& X)
{
    return (p.basis * (p.basis.transpose() * (X.colwise() - p.mean))).colwise() + p.mean;
}

class PcaShape : public ::testing::TestWithParam<std::pair<int, int>> { };

TEST_P(PcaShape, MatchesSvdOfCentredData)
{
    const auto [F, S] = GetParam();
    Rng rng(7);
    const MatrixXd X = random_matrix(F, S, rng);
    const Index d = std::min<Index>(6, std::min<Index>(F, S - 1));
    const PcaBasis p = compute_pca(X, d);
    ASSERT_EQ(p.basis.rows(), F);
    ASSERT_EQ(p.basis.cols(), d);
    EXPECT_LE((p.basis.transpose() * p.basis - MatrixXd::Identity(d, d)).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LE((p.mean - X.rowwise().mean()).cwiseAbs().maxCoeff(), 1e-15);

    const MatrixXd C = X.colwise() - X.rowwise().mean();
    Eigen::JacobiSVD<MatrixXd> svd(C, Eigen::ComputeThinU);
    for (Index i = 0; i < d; ++i) {
        EXPECT_NEAR(p.variances(i), svd.singularValues()(i) * svd.singularValues()(i) / S, 1e-10 * p.variances(0));
        // Same direction up to sign.
        EXPECT_NEAR(std::abs(p.basis.col(i).dot(svd.matrixU().col(i))), 1.0, 1e-8) << "direction " << i;
    }
    EXPECT_NEAR(p.total_variance, C.squaredNorm() / S, 1e-12 * p.total_variance);
}

// S ≤ F uses the S × S Gram matrix, S > F the F × F covariance.
INSTANTIATE_TEST_SUITE_P(Shapes, PcaShape, ::testing::Values(std::pair{40, 15}, std::pair{12, 60}));

TEST(Pca, ReproducesDataOfRankAtMostDim)
{
    Rng rng(8);
    for (const auto& [F, S] : {std::pair<Index, Index>{50, 20}, std::pair<Index, Index>{10, 80}}) {
        const MatrixXd X = low_rank_data(F, S, 5, rng);
        for (Index d : {5, 8}) {
            const PcaBasis p = compute_pca(X, d);
            EXPECT_LE((project(p, X) - X).cwiseAbs().maxCoeff(), 1e-11) << F << "x" << S << ", d = " << d;
            EXPECT_LE((p.basis.transpose() * p.basis - MatrixXd::Identity(d, d)).cwiseAbs().maxCoeff(), 1e-12);
            EXPECT_NEAR(p.explained_fraction(), 1.0, 1e-12);
            EXPECT_EQ(p.rank, 5) << F << "x" << S << ", d = " << d;  // of the data, whatever d
            for (Index i = 5; i < d; ++i) EXPECT_LE(p.variances(i), 1e-14 * p.variances(0));  // round-off only
        }
    }
}

TEST(Pca, TruncationIsOptimal)
{
    // Eckart–Young: the residual of the d-dimensional projection is Σ_{i>d} σ_i².
    Rng rng(9);
    const MatrixXd X = random_matrix(30, 20, rng);
    const MatrixXd C = X.colwise() - X.rowwise().mean();
    Eigen::JacobiSVD<MatrixXd> svd(C);
    for (Index d : {1, 4, 10}) {
        const PcaBasis p = compute_pca(X, d);
        const double expected = svd.singularValues().tail(svd.singularValues().size() - d).squaredNorm();
        EXPECT_NEAR((project(p, X) - X).squaredNorm(), expected, 1e-10 * C.squaredNorm()) << "d = " << d;
    }
}

TEST(Pca, SignsAreNormalised)
{
    Rng rng(10);
    const PcaBasis p = compute_pca(random_matrix(20, 10, rng), 4);
    for (Index j = 0; j < 4; ++j) {
        Index i = 0;
        p.basis.col(j).cwiseAbs().maxCoeff(&i);
        EXPECT_GT(p.basis(i, j), 0.0);
    }
}

TEST(Pca, RejectsBadDimensions)
{
    const MatrixXd X = MatrixXd::Ones(5, 3);
    EXPECT_THROW(compute_pca(X, 0), std::invalid_argument);
    EXPECT_THROW(compute_pca(X, 6), std::invalid_argument);
    EXPECT_THROW(compute_pca(MatrixXd(5, 0), 1), std::invalid_argument);
}

} // namespace
} // namespace lb
