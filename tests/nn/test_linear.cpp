#include <gtest/gtest.h>

#include <cmath>

#include "nn/linear.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

TEST(Linear, GradientsMatchFiniteDifferences)
{
    Rng rng(1);
    Linear layer(5, 3, rng);
    const MatrixXd X = test::random_matrix(5, 4, rng);
    test::expect_layer_gradients(layer, X, true, rng, {}, "Linear");
}

TEST(Linear, InputJacobianIsWeight)
{
    Rng rng(2);
    Linear layer(4, 6, rng);
    test::expect_layer_input_jacobian(layer, test::random_matrix(4, 1, rng).col(0), {}, "Linear");
}

TEST(Linear, GradientsAccumulateUntilZeroed)
{
    Rng rng(3);
    Linear layer(3, 2, rng);
    const MatrixXd X = test::random_matrix(3, 5, rng);
    const MatrixXd dY = test::random_matrix(2, 5, rng);
    auto params = std::vector<ParameterRef>{};
    layer.collect_parameters("", params);
    layer.forward(X, true);
    layer.backward(dY);
    const MatrixXd g1 = params[0].grad;
    layer.backward(dY);
    EXPECT_LT((params[0].grad - 2.0 * g1).norm(), 1e-12);
    layer.backward(dY, false);  // input gradient only
    EXPECT_LT((params[0].grad - 2.0 * g1).norm(), 1e-12);
}

TEST(Linear, PytorchDefaultInitBoundsAndSeeding)
{
    Rng rng(4);
    const Index in = 64, out = 300;
    Linear layer(in, out, rng);
    const double bound = 1.0 / std::sqrt(static_cast<double>(in));
    EXPECT_LE(layer.weight().cwiseAbs().maxCoeff(), bound);
    EXPECT_LE(layer.bias().cwiseAbs().maxCoeff(), bound);
    // U(−b, b): max close to the bound, mean ≈ 0, variance ≈ b²/3.
    EXPECT_GT(layer.weight().cwiseAbs().maxCoeff(), 0.99 * bound);
    EXPECT_NEAR(layer.weight().mean(), 0.0, 0.02 * bound);
    const double var = (layer.weight().array() - layer.weight().mean()).square().mean();
    EXPECT_NEAR(var, bound * bound / 3.0, 0.05 * bound * bound / 3.0);

    Rng a(7), b(7);
    EXPECT_EQ(Linear(5, 5, a).weight(), Linear(5, 5, b).weight());
}

TEST(Linear, StateDictNamesAndShapes)
{
    Rng rng(5);
    Linear layer(3, 2, rng);
    std::vector<ParameterRef> params;
    layer.collect_parameters("decoder.0.", params);
    ASSERT_EQ(params.size(), 2u);
    EXPECT_EQ(params[0].name, "decoder.0.weight");
    EXPECT_EQ(params[0].value.rows(), 2);
    EXPECT_EQ(params[0].value.cols(), 3);
    EXPECT_EQ(params[1].name, "decoder.0.bias");
    EXPECT_EQ(params[1].value.rows(), 2);
    params[0].value(1, 2) = 42.0;  // maps write through to the layer
    EXPECT_EQ(layer.weight()(1, 2), 42.0);
}

} // namespace
} // namespace lb::nn
