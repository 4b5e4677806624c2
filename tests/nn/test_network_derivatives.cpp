#include <gtest/gtest.h>

#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "nn_test_support.hpp"

namespace lb::nn {
namespace {

/// A small decoder like the paper's (residual blocks, BatchNorm, Swish, PCA output)
/// with non-trivial running statistics.
Sequential small_decoder(Rng& rng, bool output_activation = false)
{
    MlpSpec s;
    s.in_dim = 4;
    s.hidden = {9, 9};
    s.out_dim = 15;
    s.pca_dim = 5;
    s.pca_placement = PcaPlacement::output;
    s.batch_norm = true;
    s.residual = true;
    s.output_activation = output_activation;
    Sequential net = make_mlp(s, rng);
    test::randomize_batch_norm(net, rng);
    return net;
}

std::function<VectorXd(const VectorXd&)> eval_fn(Sequential& net)
{
    return [&net](const VectorXd& z) -> VectorXd { return net.forward(z, false).col(0); };
}

TEST(NetworkDerivatives, JacobianMatchesFiniteDifferences)
{
    Rng rng(61);
    Sequential net = small_decoder(rng);
    const VectorXd z = test::random_matrix(4, 1, rng).col(0);
    const MatrixXd J = jacobian(net, z);
    EXPECT_EQ(J.rows(), 15);
    EXPECT_EQ(J.cols(), 4);
    EXPECT_TRUE(lb::testing::check_jacobian(eval_fn(net), J, z, {}, "jacobian"));
}

TEST(NetworkDerivatives, VjpAndJvpMatchFiniteDifferences)
{
    Rng rng(62);
    Sequential net = small_decoder(rng);
    const VectorXd z = test::random_matrix(4, 1, rng).col(0);
    const VectorXd v = test::random_matrix(15, 1, rng).col(0);
    const VectorXd dz = test::random_matrix(4, 1, rng).col(0);
    // vjp is the gradient of the scalar vᵀ D(z).
    EXPECT_TRUE(lb::testing::check_gradient([&](const VectorXd& zz) { return v.dot(net.forward(zz, false).col(0)); },
                                            [&](const VectorXd& zz) { return vjp(net, zz, v); }, z, {}, "vjp"));
    // jvp is the directional derivative along dz: a 1-input Jacobian check.
    const VectorXd Jdz = jvp(net, z, dz);
    EXPECT_TRUE(lb::testing::check_jacobian(
        [&](const VectorXd& s) -> VectorXd { return net.forward(z + s[0] * dz, false).col(0); }, Jdz,
        VectorXd::Zero(1), {}, "jvp"));
}

TEST(NetworkDerivatives, BatchedVjpAndJvpArePerSample)
{
    Rng rng(63);
    Sequential net = small_decoder(rng);
    const Index B = 6;
    const MatrixXd Z = test::random_matrix(4, B, rng);
    const MatrixXd V = test::random_matrix(15, B, rng);
    const MatrixXd dZ = test::random_matrix(4, B, rng);
    const MatrixXd G = vjp_batch(net, Z, V);
    const MatrixXd T = jvp_batch(net, Z, dZ);
    for (Index i = 0; i < B; ++i) {
        const MatrixXd J = lb::testing::fd_jacobian(eval_fn(net), Z.col(i), 1e-6);
        EXPECT_TRUE(lb::testing::matrices_close(G.col(i), J.transpose() * V.col(i), {}, "vjp_batch column"));
        EXPECT_TRUE(lb::testing::matrices_close(T.col(i), J * dZ.col(i), {}, "jvp_batch column"));
    }
    // Parameter gradients are untouched by input derivatives.
    for (auto& p : net.parameters()) EXPECT_EQ(p.grad.cwiseAbs().sum(), 0.0) << p.name;
}

TEST(NetworkDerivatives, JacobianRowsBothModesMatchFullJacobian)
{
    Rng rng(64);
    for (bool output_activation : {false, true}) {  // Linear last layer (fast path) and generic path
        Sequential net = small_decoder(rng, output_activation);
        const VectorXd z = test::random_matrix(4, 1, rng).col(0);
        const MatrixXd J = jacobian(net, z);
        const std::vector<Index> vertex = {6, 7, 8};            // vertex 2's xyz
        const std::vector<Index> many = {0, 3, 5, 7, 9, 11, 14};  // more rows than inputs
        for (const auto& rows : {vertex, many}) {
            MatrixXd expected(static_cast<Index>(rows.size()), 4);
            for (std::size_t i = 0; i < rows.size(); ++i) expected.row(static_cast<Index>(i)) = J.row(rows[i]);
            for (auto mode : {JacobianMode::automatic, JacobianMode::forward, JacobianMode::reverse}) {
                const MatrixXd Jr = jacobian_rows(net, z, rows, mode);
                EXPECT_LT((Jr - expected).cwiseAbs().maxCoeff(), 1e-12)
                    << "mode " << static_cast<int>(mode) << " output_activation " << output_activation;
            }
        }
        EXPECT_THROW(jacobian_rows(net, z, {15}), std::out_of_range);
    }
}

} // namespace
} // namespace lb::nn
