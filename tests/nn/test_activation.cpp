#include <gtest/gtest.h>

#include "core/error.hpp"
#include "nn/activation.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

TEST(Activation, SwishValues)
{
    Swish swish;
    MatrixXd X(3, 1);
    X << 0.0, 1.0, -2.0;
    const MatrixXd Y = swish.forward(X, false);
    EXPECT_DOUBLE_EQ(Y(0, 0), 0.0);
    EXPECT_NEAR(Y(1, 0), 0.7310585786300049, 1e-15);   // 1·σ(1)
    EXPECT_NEAR(Y(2, 0), -0.2384058440442351, 1e-15);  // −2·σ(−2)
    EXPECT_EQ(swish.type_name(), "Swish");
}

TEST(Activation, SwishGradients)
{
    Rng rng(11);
    Swish swish;
    const MatrixXd X = test::random_matrix(6, 4, rng, -4.0, 4.0);
    test::expect_layer_gradients(swish, X, true, rng, {}, "Swish");
    test::expect_layer_input_jacobian(swish, X.col(0), {}, "Swish");
}

TEST(Activation, TanhAndReluGradients)
{
    Rng rng(12);
    Activation tanh_layer(ActivationKind::tanh);
    test::expect_layer_gradients(tanh_layer, test::random_matrix(5, 3, rng, -2.0, 2.0), true, rng, {}, "Tanh");
    // ReLU away from its kink.
    Activation relu(ActivationKind::relu);
    MatrixXd X = test::random_matrix(5, 3, rng, 0.1, 1.0);
    X.row(1) *= -1.0;
    test::expect_layer_gradients(relu, X, true, rng, {}, "ReLU");
}

TEST(Activation, NamesRoundTrip)
{
    for (auto k : {ActivationKind::identity, ActivationKind::swish, ActivationKind::tanh, ActivationKind::relu})
        EXPECT_EQ(activation_from_string(to_string(k)), k);
    EXPECT_EQ(activation_from_string("silu"), ActivationKind::swish);
    EXPECT_THROW(activation_from_string("gelu"), ConfigError);
}

} // namespace
} // namespace lb::nn
