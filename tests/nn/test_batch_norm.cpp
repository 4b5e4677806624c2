#include <gtest/gtest.h>

#include <stdexcept>

#include "nn/batch_norm.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

TEST(BatchNorm1d, TrainingModeGradientsThroughBatchStatistics)
{
    Rng rng(21);
    BatchNorm1d bn(4);
    bn.weight() = test::random_matrix(4, 1, rng, 0.5, 1.5).col(0);
    bn.bias() = test::random_matrix(4, 1, rng).col(0);
    const MatrixXd X = test::random_matrix(4, 7, rng, -2.0, 3.0);
    test::expect_layer_gradients(bn, X, true, rng, {}, "BatchNorm1d(train)");
}

TEST(BatchNorm1d, EvalModeGradientsAndJacobian)
{
    Rng rng(22);
    BatchNorm1d bn(3);
    bn.weight() = test::random_matrix(3, 1, rng, 0.5, 1.5).col(0);
    bn.bias() = test::random_matrix(3, 1, rng).col(0);
    bn.running_mean() = test::random_matrix(3, 1, rng).col(0);
    bn.running_var() = test::random_matrix(3, 1, rng, 0.2, 2.0).col(0);
    test::expect_layer_gradients(bn, test::random_matrix(3, 5, rng), false, rng, {}, "BatchNorm1d(eval)");
    test::expect_layer_input_jacobian(bn, test::random_matrix(3, 1, rng).col(0), {}, "BatchNorm1d(eval)");
}

TEST(BatchNorm1d, TrainingNormalisesAndUpdatesRunningStatsLikePytorch)
{
    BatchNorm1d bn(2);
    MatrixXd X(2, 4);
    X << 1, 2, 3, 4,      // mean 2.5, biased var 1.25, unbiased 5/3
        -1, -1, -1, 3;    // mean 0, biased var 3, unbiased 4
    const MatrixXd Y = bn.forward(X, true);
    EXPECT_NEAR(Y.row(0).mean(), 0.0, 1e-14);
    EXPECT_NEAR(Y.row(0).squaredNorm() / 4.0, 1.25 / (1.25 + 1e-5), 1e-12);
    EXPECT_NEAR(bn.running_mean()[0], 0.1 * 2.5, 1e-15);
    EXPECT_NEAR(bn.running_mean()[1], 0.0, 1e-15);
    EXPECT_NEAR(bn.running_var()[0], 0.9 + 0.1 * 5.0 / 3.0, 1e-15);
    EXPECT_NEAR(bn.running_var()[1], 0.9 + 0.1 * 4.0, 1e-15);
    EXPECT_EQ(bn.num_batches_tracked(), 1);
    bn.forward(X, true);
    EXPECT_NEAR(bn.running_mean()[0], 0.9 * 0.25 + 0.25, 1e-15);
    EXPECT_EQ(bn.num_batches_tracked(), 2);

    // Eval mode uses the running statistics and leaves them unchanged.
    const VectorXd rm = bn.running_mean(), rv = bn.running_var();
    const MatrixXd Ye = bn.forward(X, false);
    EXPECT_NEAR(Ye(0, 0), (1.0 - rm[0]) / std::sqrt(rv[0] + 1e-5), 1e-14);
    EXPECT_EQ(bn.running_mean(), rm);
    EXPECT_EQ(bn.num_batches_tracked(), 2);
}

TEST(BatchNorm1d, RejectsSingleSampleTrainingAndTrainingTangent)
{
    BatchNorm1d bn(3);
    EXPECT_THROW(bn.forward(MatrixXd::Ones(3, 1), true), std::invalid_argument);
    bn.forward(MatrixXd::Random(3, 4), true);
    EXPECT_THROW(bn.tangent(MatrixXd::Ones(3, 4)), std::logic_error);
}

TEST(BatchNorm1d, EvalAffineMapMatchesForward)
{
    Rng rng(23);
    BatchNorm1d bn(5);
    bn.weight() = test::random_matrix(5, 1, rng).col(0);
    bn.bias() = test::random_matrix(5, 1, rng).col(0);
    bn.running_mean() = test::random_matrix(5, 1, rng).col(0);
    bn.running_var() = test::random_matrix(5, 1, rng, 0.1, 3.0).col(0);
    const MatrixXd X = test::random_matrix(5, 3, rng);
    const MatrixXd expected = (X.array().colwise() * bn.eval_scale().array()).colwise() + bn.eval_shift().array();
    EXPECT_LT((bn.forward(X, false) - expected).cwiseAbs().maxCoeff(), 1e-14);
}

} // namespace
} // namespace lb::nn
