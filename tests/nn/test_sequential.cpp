#include <gtest/gtest.h>

#include <stdexcept>

#include "nn/batch_norm.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/sequential.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

MlpSpec small_decoder_spec()
{
    MlpSpec s;
    s.in_dim = 3;
    s.hidden = {6, 6};
    s.out_dim = 12;
    s.pca_dim = 4;
    s.pca_placement = PcaPlacement::output;
    s.batch_norm = true;
    s.residual = true;
    return s;
}

TEST(Sequential, WholeNetworkGradientsTrainingWithBatchNorm)
{
    Rng rng(41);
    Sequential net = make_mlp(small_decoder_spec(), rng);
    test::expect_layer_gradients(net, test::random_matrix(3, 6, rng), true, rng, {}, "residual MLP (train)");
}

TEST(Sequential, WholeNetworkGradientsEvalPlainMlp)
{
    Rng rng(42);
    MlpSpec s;
    s.in_dim = 5;
    s.hidden = {7, 7, 7};
    s.out_dim = 2;
    s.batch_norm = true;
    Sequential net = make_mlp(s, rng);
    net.forward(test::random_matrix(5, 10, rng, -2, 2), true);
    test::expect_layer_gradients(net, test::random_matrix(5, 4, rng), false, rng, {}, "plain MLP (eval)");
}

TEST(Sequential, AddChecksWidths)
{
    Rng rng(43);
    Sequential net;
    net.emplace<Linear>(3, 4, rng);
    net.emplace<BatchNorm1d>(4);
    EXPECT_THROW(net.emplace<Linear>(5, 2, rng), std::invalid_argument);
    EXPECT_EQ(net.in_features(), 3);
    EXPECT_EQ(net.out_features(), 4);
}

TEST(Sequential, CopyIsDeep)
{
    Rng rng(44);
    Sequential a = make_mlp(small_decoder_spec(), rng);
    Sequential b = a;
    const MatrixXd X = test::random_matrix(3, 2, rng);
    const MatrixXd ya = a.forward(X, false);
    b.parameters()[0].value.array() += 1.0;
    EXPECT_EQ(a.forward(X, false), ya);
    EXPECT_NE(b.forward(X, false), ya);
}

TEST(Sequential, ZeroGradAndParameterCount)
{
    Rng rng(45);
    Sequential net;
    net.emplace<Linear>(3, 4, rng);
    net.emplace<Swish>();
    net.emplace<Linear>(4, 2, rng);
    EXPECT_EQ(net.num_parameters(), 3 * 4 + 4 + 4 * 2 + 2);
    net.forward(MatrixXd::Ones(3, 2), true);
    net.backward(MatrixXd::Ones(2, 2));
    double total = 0;
    for (auto& p : net.parameters()) total += p.grad.cwiseAbs().sum();
    EXPECT_GT(total, 0.0);
    net.zero_grad();
    for (auto& p : net.parameters()) EXPECT_EQ(p.grad.cwiseAbs().sum(), 0.0) << p.name;
    EXPECT_EQ(net.parameters("encoder.")[2].name, "encoder.2.weight");
}

} // namespace
} // namespace lb::nn
