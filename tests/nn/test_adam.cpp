#include <gtest/gtest.h>

#include <cmath>

#include "nn/adam.hpp"
#include "nn/linear.hpp"

namespace lb::nn {
namespace {

ParameterRef ref(const std::string& name, MatrixXd& value, MatrixXd& grad)
{
    return {name, Eigen::Map<MatrixXd>(value.data(), value.rows(), value.cols()),
            Eigen::Map<MatrixXd>(grad.data(), grad.rows(), grad.cols())};
}

TEST(Adam, MinimisesAnIllConditionedQuadratic)
{
    // f(θ) = ½ Σ a_i (θ_i − c_i)², a spanning 4 orders of magnitude.
    MatrixXd theta = MatrixXd::Zero(4, 1), grad = MatrixXd::Zero(4, 1);
    VectorXd a(4), c(4);
    a << 100.0, 1.0, 0.1, 0.01;
    c << 1.0, -2.0, 0.5, 3.0;
    AdamOptions opt;
    opt.lr = 0.05;
    Adam adam({ref("theta", theta, grad)}, opt);
    for (int it = 0; it < 4000; ++it) {
        adam.zero_grad();
        grad.col(0) = a.cwiseProduct(theta.col(0) - c);
        adam.step();
    }
    EXPECT_LT((theta.col(0) - c).cwiseAbs().maxCoeff(), 1e-3);
    EXPECT_EQ(adam.steps(), 4000);
}

TEST(Adam, FirstStepIsLearningRateTimesSign)
{
    // After one step m̂ = g and v̂ = g², so Δθ = −lr g/(|g| + ε).
    MatrixXd theta = MatrixXd::Zero(3, 1), grad(3, 1);
    grad << 2.0, -0.5, 1e-3;
    Adam adam({ref("theta", theta, grad)}, {0.1, 0.9, 0.999, 1e-8, 0.0});
    adam.step();
    for (Index i = 0; i < 3; ++i)
        EXPECT_NEAR(theta(i, 0), -0.1 * grad(i, 0) / (std::abs(grad(i, 0)) + 1e-8), 1e-12);
}

TEST(Adam, WeightDecayShrinksWithZeroGradient)
{
    MatrixXd theta = MatrixXd::Constant(2, 2, 1.0), grad = MatrixXd::Zero(2, 2);
    AdamOptions opt;
    opt.lr = 0.01;
    opt.weight_decay = 0.1;
    Adam adam({ref("w", theta, grad)}, opt);
    for (int i = 0; i < 10; ++i) adam.step();
    EXPECT_LT(theta.maxCoeff(), 1.0 - 0.05);
    EXPECT_GT(theta.minCoeff(), 0.0);
}

TEST(Adam, TrainsALinearLayerOnNetworkParameters)
{
    // Fit y = A x + b with a Linear layer through its ParameterRefs.
    Rng rng(71);
    Linear layer(3, 2, rng);
    MatrixXd A(2, 3);
    A << 1, -2, 0.5, 0.3, 0.7, -1;
    VectorXd b(2);
    b << 0.2, -0.4;
    MatrixXd X = MatrixXd::Random(3, 64);
    MatrixXd Y = (A * X).colwise() + b;
    std::vector<ParameterRef> params;
    layer.collect_parameters("", params);
    AdamOptions opt;
    opt.lr = 0.02;
    Adam adam(params, opt);
    double loss = 0;
    for (int it = 0; it < 3000; ++it) {
        adam.zero_grad();
        const MatrixXd R = layer.forward(X, true) - Y;
        loss = R.squaredNorm() / X.cols();
        layer.backward(2.0 * R / X.cols());
        adam.step();
    }
    EXPECT_LT(loss, 1e-8);
    EXPECT_LT((layer.weight() - A).cwiseAbs().maxCoeff(), 1e-4);
}

} // namespace
} // namespace lb::nn

namespace lb::nn {
namespace {

TEST(Adam, StateRestoreResumesBitForBit)
{
    Rng rng(72);
    auto make = [] {
        MatrixXd theta(2, 3);
        theta << 1, -2, 3, 0.5, 0.25, -1;
        return theta;
    };
    MatrixXd a = make(), ga = MatrixXd::Zero(2, 3), b = make(), gb = MatrixXd::Zero(2, 3);
    AdamOptions opt;
    opt.lr = 0.01;
    opt.weight_decay = 0.01;
    Adam adam_a({ref("w", a, ga)}, opt);
    auto gradient = [](const MatrixXd& t) -> MatrixXd { return t.array().sin() + 0.1 * t.array().square(); };
    for (int i = 0; i < 5; ++i) {
        ga.noalias() = gradient(a);
        adam_a.step();
    }
    // Checkpoint: parameters and optimiser state into a fresh optimiser.
    b = a;
    Adam adam_b({ref("w", b, gb)}, opt);
    adam_b.set_state(adam_a.state());
    EXPECT_EQ(adam_b.steps(), 5);
    for (int i = 0; i < 5; ++i) {
        ga.noalias() = gradient(a);
        adam_a.step();
        gb.noalias() = gradient(b);
        adam_b.step();
    }
    EXPECT_EQ(a, b);
    AdamState bad = adam_a.state();
    bad.m[0] = MatrixXd::Zero(3, 2);
    EXPECT_THROW(adam_b.set_state(bad), std::invalid_argument);
    bad.m.clear();
    EXPECT_THROW(adam_b.set_state(bad), std::invalid_argument);
}

} // namespace
} // namespace lb::nn
