#include <gtest/gtest.h>

#include "nn/residual_block.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

TEST(ResidualBlock, GradientsWithProjectionTraining)
{
    Rng rng(31);
    ResidualBlock block(4, 6, true, ActivationKind::swish, rng);
    ASSERT_TRUE(block.has_projection());
    test::expect_layer_gradients(block, test::random_matrix(4, 5, rng), true, rng, {}, "ResidualBlock(4->6, train)");
}

TEST(ResidualBlock, GradientsIdentitySkipEvalAndJacobian)
{
    Rng rng(32);
    ResidualBlock block(5, 5, true, ActivationKind::swish, rng);
    ASSERT_FALSE(block.has_projection());
    block.forward(test::random_matrix(5, 8, rng, -2, 2), true);  // non-trivial running stats
    test::expect_layer_gradients(block, test::random_matrix(5, 3, rng), false, rng, {}, "ResidualBlock(5->5, eval)");
    test::expect_layer_input_jacobian(block, test::random_matrix(5, 1, rng).col(0), {}, "ResidualBlock");
}

TEST(ResidualBlock, WithoutBatchNormIsSkipPlusMlp)
{
    Rng rng(33);
    ResidualBlock block(3, 3, false, ActivationKind::tanh, rng);
    EXPECT_EQ(block.f().size(), 3);  // Linear, Tanh, Linear
    const MatrixXd X = test::random_matrix(3, 2, rng);
    Sequential f = block.f();
    EXPECT_LT((block.forward(X, false) - (X + f.forward(X, false))).norm(), 1e-14);
    test::expect_layer_gradients(block, X, true, rng, {}, "ResidualBlock(no bn)");
}

TEST(ResidualBlock, ParameterNames)
{
    Rng rng(34);
    ResidualBlock block(2, 3, true, ActivationKind::swish, rng);
    std::vector<ParameterRef> params;
    block.collect_parameters("decoder.0.", params);
    std::vector<std::string> names;
    for (auto& p : params) names.push_back(p.name);
    const std::vector<std::string> expected = {
        "decoder.0.f.0.weight", "decoder.0.f.0.bias", "decoder.0.f.1.weight", "decoder.0.f.1.bias",
        "decoder.0.f.3.weight", "decoder.0.f.3.bias", "decoder.0.f.4.weight", "decoder.0.f.4.bias",
        "decoder.0.skip.weight", "decoder.0.skip.bias"};
    EXPECT_EQ(names, expected);
    std::vector<BufferRef> buffers;
    block.collect_buffers("decoder.0.", buffers);
    ASSERT_EQ(buffers.size(), 6u);
    EXPECT_EQ(buffers[0].name, "decoder.0.f.1.running_mean");
    EXPECT_EQ(buffers[5].name, "decoder.0.f.4.num_batches_tracked");
}

} // namespace
} // namespace lb::nn
