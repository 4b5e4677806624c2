#pragma once
// Helpers shared by the lb::nn tests: the layer gradient harness (built on THE
// generic finite-difference checker, tests/support/finite_difference.hpp) and
// randomisation of BatchNorm state so eval-mode paths are non-trivial.
#include <string>

#include <gtest/gtest.h>

#include "core/rng.hpp"
#include "nn/layer.hpp"
#include "nn/sequential.hpp"
#include "support/finite_difference.hpp"

namespace lb::nn::test {

inline MatrixXd random_matrix(Index rows, Index cols, Rng& rng, double lo = -1.0, double hi = 1.0)
{
    MatrixXd m(rows, cols);
    for (Index j = 0; j < cols; ++j)
        for (Index i = 0; i < rows; ++i) m(i, j) = rng.uniform(lo, hi);
    return m;
}

inline VectorXd flat(const MatrixXd& m) { return Eigen::Map<const VectorXd>(m.data(), m.size()); }
inline MatrixXd unflat(const VectorXd& v, Index rows, Index cols) { return Eigen::Map<const MatrixXd>(v.data(), rows, cols); }

/// Scalar loss L = Σ Wt ⊙ layer.forward(X, training) with random Wt. Checks
///  * dL/dX from layer.backward(Wt) against central differences in X, and
///  * dL/dθ accumulated into every parameter's gradient against differences in θ.
inline void expect_layer_gradients(Layer& layer, const MatrixXd& X, bool training, Rng& rng,
                                   const lb::testing::FdOptions& opt = {}, const std::string& what = "layer")
{
    const MatrixXd Y = layer.forward(X, training);
    const MatrixXd Wt = random_matrix(Y.rows(), Y.cols(), rng);
    auto loss_at = [&](const MatrixXd& Xp) { return (layer.forward(Xp, training).array() * Wt.array()).sum(); };

    std::vector<ParameterRef> params;
    layer.collect_parameters("", params);
    for (auto& p : params) p.grad.setZero();
    layer.forward(X, training);
    const MatrixXd dX = layer.backward(Wt, true);
    std::vector<MatrixXd> grads;
    for (auto& p : params) grads.push_back(p.grad);

    EXPECT_TRUE(lb::testing::check_gradient(
        [&](const VectorXd& x) { return loss_at(unflat(x, X.rows(), X.cols())); },
        [&](const VectorXd&) { return flat(dX); }, flat(X), opt, what + ": dL/dX"));

    for (std::size_t i = 0; i < params.size(); ++i) {
        auto& p = params[i];
        const MatrixXd original = p.value;
        EXPECT_TRUE(lb::testing::check_gradient(
            [&](const VectorXd& theta) {
                p.value = unflat(theta, original.rows(), original.cols());
                const double l = loss_at(X);
                p.value = original;
                return l;
            },
            [&](const VectorXd&) { return flat(grads[i]); }, flat(original), opt, what + ": dL/d" + p.name));
        p.value = original;
    }
}

/// Per-sample input Jacobian in eval mode: tangent(I) (forward mode) and
/// backward(I, false)ᵀ (reverse mode with several seeds) against differences.
inline void expect_layer_input_jacobian(Layer& layer, const VectorXd& x, const lb::testing::FdOptions& opt = {},
                                        const std::string& what = "layer")
{
    auto f = [&](const VectorXd& xp) -> VectorXd { return layer.forward(xp, false).col(0); };
    const Index out = f(x).size();
    layer.forward(x, false);
    const MatrixXd J_fwd = layer.tangent(MatrixXd::Identity(x.size(), x.size()));
    layer.forward(x, false);
    const MatrixXd J_rev = layer.backward(MatrixXd::Identity(out, out), false).transpose();
    EXPECT_TRUE(lb::testing::check_jacobian(f, J_fwd, x, opt, what + ": tangent"));
    EXPECT_TRUE(lb::testing::check_jacobian(f, J_rev, x, opt, what + ": backward seeds"));
}

/// Give every BatchNorm non-trivial affine parameters and running statistics.
inline void randomize_batch_norm(Sequential& net, Rng& rng)
{
    for (auto& b : net.buffers()) {
        if (b.integer) continue;
        if (b.name.find("running_var") != std::string::npos)
            b.value = random_matrix(b.value.rows(), 1, rng, 0.3, 2.0);
        else
            b.value = random_matrix(b.value.rows(), 1, rng, -0.5, 0.5);
    }
    // BatchNorm weight/bias are the n×1 parameters whose sibling has a running_mean.
    std::vector<std::string> bn_prefixes;
    for (auto& b : net.buffers())
        if (b.name.size() > 12 && b.name.compare(b.name.size() - 12, 12, "running_mean") == 0)
            bn_prefixes.push_back(b.name.substr(0, b.name.size() - 12));
    for (auto& p : net.parameters())
        for (const auto& pre : bn_prefixes)
            if (p.name == pre + "weight")
                p.value = random_matrix(p.value.rows(), 1, rng, 0.5, 1.5);
            else if (p.name == pre + "bias")
                p.value = random_matrix(p.value.rows(), 1, rng, -0.3, 0.3);
}

} // namespace lb::nn::test
