#include <gtest/gtest.h>

#include <omp.h>

#include "nn/batch_norm.hpp"
#include "nn/inference_network.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "paper/paper_architectures.hpp"
#include "nn/residual_block.hpp"
#include "nn_test_support.hpp"
#include "support/heap_counter.hpp"

namespace lb::nn {
namespace {

using testing::HeapCounter;

/// ‖a − b‖∞ / max(‖b‖∞, 1e-30)
double relative_error(const VectorXd& a, const VectorXd& b)
{
    return (a - b).cwiseAbs().maxCoeff() / std::max(b.cwiseAbs().maxCoeff(), 1e-30);
}

TEST(InferenceNetwork, AllocationCounterSeesAllocations)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    HeapCounter counter;
    VectorXd v = VectorXd::Ones(1000);
    EXPECT_GT(counter.count(), 0) << "malloc interposition is not active, the no-allocation test would be vacuous";
    EXPECT_EQ(v.sum(), 1000.0);
}

TEST(InferenceNetwork, MatchesDoubleForwardOnTable2Architectures)
{
    for (const auto& arch : table2_architectures()) {
        Rng rng(81);
        Sequential decoder = make_mlp(arch.decoder, rng);
        Sequential integrator = make_mlp(arch.integrator, rng);
        test::randomize_batch_norm(decoder, rng);
        InferenceNetwork dec_f(decoder);
        InferenceNetwork int_f(integrator);
        InferenceNetworkD dec_d(decoder);
        for (int trial = 0; trial < 3; ++trial) {
            const VectorXd q = test::random_matrix(arch.integrator.in_dim, 1, rng, -2, 2).col(0);
            const VectorXd z_ref = integrator.forward(q, false).col(0);
            const VectorXd z_f = int_f.evaluate(q.cast<float>()).cast<double>();
            EXPECT_LT(relative_error(z_f, z_ref), 1e-5) << arch.name << " integrator";

            const VectorXd x_ref = decoder.forward(z_ref, false).col(0);
            const VectorXd x_f = dec_f.evaluate(z_ref.cast<float>()).cast<double>();
            const VectorXd x_d = dec_d.evaluate(z_ref);
            EXPECT_LT(relative_error(x_f, x_ref), 1e-4) << arch.name << " decoder (float)";
            EXPECT_LT(relative_error(x_d, x_ref), 1e-12) << arch.name << " decoder (double)";
        }
        if (arch.name == "armadillo") {
            // BatchNorms folded, activations fused: 9 GEMVs and the 2 identity skips.
            const auto& ops = dec_f.ops();
            EXPECT_EQ(ops.size(), 11u) << dec_f.describe();
            EXPECT_EQ(dec_f.multiply_adds(), 12 * 200 * 2 + 200 * 200 * 5 + 200 * 50 + 50 * 10020);
        }
    }
}

TEST(InferenceNetwork, FoldsTheInputStandardizer)
{
    Rng rng(82);
    MlpSpec s;
    s.in_dim = 7;
    s.hidden = {16, 16};
    s.out_dim = 3;
    Sequential net = make_mlp(s, rng);
    const MatrixXd data = test::random_matrix(7, 50, rng, -5.0, 20.0);
    const Standardizer standardizer = Standardizer::fit(data);
    InferenceNetworkD fast(net, &standardizer);
    EXPECT_EQ(fast.ops().size(), 3u) << fast.describe();  // three affine ops, no separate scale
    const VectorXd x = data.col(3);
    const VectorXd expected = net.forward(standardizer.apply(x), false).col(0);
    EXPECT_LT(relative_error(fast.evaluate(x), expected), 1e-12);
}

/// Leading BatchNorm and activation, a BatchNorm after an identity-skip block,
/// activations not preceded by a Linear, an output activation; with `head`, a final
/// Linear + BatchNorm (foldable) after the last activation.
Sequential unfoldable_network(Rng& rng, bool head)
{
    Sequential net;
    net.emplace<BatchNorm1d>(5);
    net.emplace<Activation>(ActivationKind::tanh);
    net.emplace<Linear>(5, 8, rng);
    net.emplace<ResidualBlock>(8, 8, true, ActivationKind::swish, rng);
    net.emplace<BatchNorm1d>(8);
    net.emplace<Swish>();
    net.emplace<ResidualBlock>(8, 6, false, ActivationKind::relu, rng);
    net.emplace<Activation>(ActivationKind::tanh);
    if (head) {
        net.emplace<Linear>(6, 4, rng);
        net.emplace<BatchNorm1d>(4);
    }
    return net;
}

TEST(InferenceNetwork, HandlesUnfoldableLayers)
{
    Rng rng(83);
    Sequential net = unfoldable_network(rng, true);
    test::randomize_batch_norm(net, rng);
    InferenceNetworkD fast_d(net);
    InferenceNetwork fast_f(net);
    for (int trial = 0; trial < 5; ++trial) {
        const VectorXd x = test::random_matrix(5, 1, rng, -2, 2).col(0);
        const VectorXd expected = net.forward(x, false).col(0);
        EXPECT_LT(relative_error(fast_d.evaluate(x), expected), 1e-12) << fast_d.describe();
        EXPECT_LT(relative_error(fast_f.evaluate(x.cast<float>()).cast<double>(), expected), 1e-5);
    }
    // The leading BatchNorm folds forward into the Linear only through the tanh: it must stay.
    bool has_scale = false;
    for (const auto& op : fast_d.ops()) has_scale |= op.kind == InferenceOpKind::scale;
    EXPECT_TRUE(has_scale);
}

TEST(InferenceNetwork, JacobianRowsMatchDoublePath)
{
    Rng rng(84);
    for (bool output_activation : {false, true}) {
        MlpSpec s = table2_architecture("cloth").decoder;
        s.output_activation = output_activation;
        Sequential net = make_mlp(s, rng);
        test::randomize_batch_norm(net, rng);
        InferenceNetwork fast_f(net);
        InferenceNetworkD fast_d(net);
        const VectorXd z = test::random_matrix(4, 1, rng).col(0);
        const std::vector<Index> vertex = {30, 31, 32};
        const std::vector<Index> many = {0, 1, 2, 100, 101, 575};
        for (const auto& rows : {vertex, many}) {
            const MatrixXd expected = jacobian_rows(net, z, rows);
            for (auto mode : {JacobianMode::forward, JacobianMode::reverse}) {
                MatrixXf Jf(static_cast<Index>(rows.size()), 4);
                MatrixXd Jd(static_cast<Index>(rows.size()), 4);
                fast_f.jacobian_rows(z.cast<float>(), rows, Jf, mode);
                fast_d.jacobian_rows(z, rows, Jd, mode);
                const double scale = expected.cwiseAbs().maxCoeff();
                EXPECT_LT((Jd - expected).cwiseAbs().maxCoeff(), 1e-12 * scale);
                EXPECT_LT((Jf.cast<double>() - expected).cwiseAbs().maxCoeff(), 1e-4 * scale);
            }
        }
    }
}

/// Batched forward and VJP (the frozen decoder of the training losses) against the
/// Sequential's eval-mode forward and nn::vjp_batch, on the paper decoders and on a
/// network with every op kind (scale, act, add, an output activation).
TEST(InferenceNetwork, BatchedForwardAndVjpMatchSequential)
{
    Rng rng(85);
    std::vector<std::pair<std::string, Sequential>> nets;
    for (const auto& arch : table2_architectures()) nets.emplace_back(arch.name, make_mlp(arch.decoder, rng));
    nets.emplace_back("unfoldable", unfoldable_network(rng, false));
    for (auto& [name, net] : nets) {
        test::randomize_batch_norm(net, rng);
        InferenceNetworkD fast_d(net);
        InferenceNetwork fast_f(net);
        const Index in = fast_d.in_features(), out = fast_d.out_features();
        for (Index B : {Index(1), Index(37)}) {
            const MatrixXd Z = test::random_matrix(in, B, rng, -2, 2);
            const MatrixXd V = test::random_matrix(out, B, rng, -1, 1);
            const MatrixXd Y_ref = net.forward(Z, false);
            const MatrixXd G_ref = vjp_batch(net, Z, V);
            const MatrixXd Y = fast_d.forward_batch(Z, true);
            const MatrixXd G = fast_d.vjp_batch(V);
            ASSERT_EQ(Y.rows(), out);
            ASSERT_EQ(G.rows(), in);
            ASSERT_EQ(G.cols(), B);
            const double y_scale = Y_ref.cwiseAbs().maxCoeff(), g_scale = G_ref.cwiseAbs().maxCoeff();
            EXPECT_LT((Y - Y_ref).cwiseAbs().maxCoeff(), 1e-12 * y_scale) << name << " B=" << B;
            EXPECT_LT((G - G_ref).cwiseAbs().maxCoeff(), 1e-12 * g_scale) << name << " B=" << B;
            // A second call reuses the buffers and must give the same numbers.
            const MatrixXd Y2 = fast_d.forward_batch(Z, true);
            const MatrixXd G2 = fast_d.vjp_batch(V);
            EXPECT_EQ((Y2 - Y).cwiseAbs().maxCoeff(), 0.0) << name;
            EXPECT_EQ((G2 - G).cwiseAbs().maxCoeff(), 0.0) << name;
            const MatrixXf Yf = fast_f.forward_batch(Z.cast<float>(), true);
            const MatrixXf Gf = fast_f.vjp_batch(V.cast<float>());
            EXPECT_LT((Yf.cast<double>() - Y_ref).cwiseAbs().maxCoeff(), 1e-4 * y_scale) << name << " (float)";
            EXPECT_LT((Gf.cast<double>() - G_ref).cwiseAbs().maxCoeff(), 1e-4 * g_scale) << name << " (float)";
        }
        // A VJP needs a recorded forward of as many columns.
        fast_d.forward_batch(MatrixXd::Zero(in, 3), false);
        EXPECT_THROW(fast_d.vjp_batch(MatrixXd::Zero(out, 3)), std::invalid_argument) << name;
        fast_d.forward_batch(MatrixXd::Zero(in, 3), true);
        EXPECT_THROW(fast_d.vjp_batch(MatrixXd::Zero(out, 4)), std::invalid_argument) << name;
        EXPECT_THROW(fast_d.forward_batch(MatrixXd::Zero(in + 1, 3)), std::invalid_argument) << name;
    }
}

/// The batched passes give the same numbers bit for bit on one thread and on several: the
/// column blocks' inner edges fall on whole GEMM panels. Batch sizes whose halves and thirds
/// are not multiples of 4 put a block edge inside a panel if the edges are not rounded.
TEST(InferenceNetwork, BatchedPassesDoNotDependOnTheThreadCount)
{
    Rng rng(86);
    Sequential net = make_mlp(table2_architectures().front().decoder, rng);
    test::randomize_batch_norm(net, rng);
    InferenceNetworkD fast_d(net);
    InferenceNetwork fast_f(net);
    const Index in = fast_d.in_features(), out = fast_d.out_features();
    const int threads_before = omp_get_max_threads();
    for (Index B : {Index(203), Index(298), Index(499)}) {
        const MatrixXd Z = test::random_matrix(in, B, rng, -2, 2);
        const MatrixXd V = test::random_matrix(out, B, rng, -1, 1);
        std::vector<MatrixXd> Y(3), G(3);
        std::vector<MatrixXf> Yf(3), Gf(3);
        for (int t = 1; t <= 3; ++t) {
            omp_set_num_threads(t);
            Y[size_t(t - 1)] = fast_d.forward_batch(Z, true);
            G[size_t(t - 1)] = fast_d.vjp_batch(V);
            Yf[size_t(t - 1)] = fast_f.forward_batch(Z.cast<float>(), true);
            Gf[size_t(t - 1)] = fast_f.vjp_batch(V.cast<float>());
        }
        for (size_t t = 1; t < 3; ++t) {
            EXPECT_TRUE((Y[t].array() == Y[0].array()).all()) << "B=" << B << ", " << t + 1 << " threads";
            EXPECT_TRUE((G[t].array() == G[0].array()).all()) << "B=" << B << ", " << t + 1 << " threads";
            EXPECT_TRUE((Yf[t].array() == Yf[0].array()).all()) << "B=" << B << ", " << t + 1 << " threads (float)";
            EXPECT_TRUE((Gf[t].array() == Gf[0].array()).all()) << "B=" << B << ", " << t + 1 << " threads (float)";
        }
    }
    omp_set_num_threads(threads_before);
}

TEST(InferenceNetwork, EvaluateAndJacobianRowsDoNotAllocate)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    Rng rng(85);
    const auto arch = table2_architecture("armadillo");
    Sequential decoder = make_mlp(arch.decoder, rng);
    Sequential integrator = make_mlp(arch.integrator, rng);
    const Standardizer standardizer(arch.integrator.in_dim);
    InferenceNetwork dec(decoder);
    InferenceNetwork integ(integrator, &standardizer);
    VectorXf q = VectorXf::Random(arch.integrator.in_dim);
    VectorXf x(arch.full_dof);
    const std::vector<Index> vertex = {300, 301, 302};
    MatrixXf J(3, arch.latent_dim);
    VectorXf z(arch.latent_dim);
    integ.evaluate(q.data(), z.data());
    dec.jacobian_rows(z, vertex, J);  // sizes the derivative workspaces
    float checksum = 0;
    long allocations = 0;
    {
        HeapCounter counter;
        for (int frame = 0; frame < 20; ++frame) {
            integ.evaluate(q.data(), z.data());
            dec.evaluate(z.data(), x.data());
            checksum += x[0] + dec.evaluate(z)[5];
            dec.jacobian_rows(z, vertex, J);
            checksum += J(0, 0);
        }
        allocations = counter.count();
    }
    EXPECT_EQ(allocations, 0);
    EXPECT_TRUE(std::isfinite(checksum));
}

// The batched passes of the trainer's frozen decoder (the paper's armadillo decoder, whose
// output-layer GEMM packs megabytes) allocate nothing once their buffers have grown to the
// batch sizes in use (the largest column block of each: 127 columns split 56 + 71 on two
// threads), whatever order they come in: the near-equal batches of an epoch differ by a
// column, and the noisy half and the whole batch alternate.
TEST(InferenceNetwork, BatchedPassesAllocateNothingOnceGrown)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    Rng rng(87);
    const auto arch = table2_architectures().back();
    for (bool float32 : {false, true}) {
        Sequential net = make_mlp(arch.decoder, rng);
        InferenceNetworkD fast_d(net);
        InferenceNetwork fast_f(net);
        const Index in = fast_d.in_features(), out = fast_d.out_features();
        const MatrixXd Z = test::random_matrix(in, 128, rng, -2, 2);
        const MatrixXd V = test::random_matrix(out, 128, rng, -1, 1);
        const MatrixXf Zf = Z.cast<float>(), Vf = V.cast<float>();
        auto pass = [&](Index columns) {
            if (float32) {
                fast_f.forward_batch(Zf.leftCols(columns), true);
                return double(fast_f.vjp_batch(Vf.leftCols(columns))(0, 0));
            }
            fast_d.forward_batch(Z.leftCols(columns), true);
            return fast_d.vjp_batch(V.leftCols(columns))(0, 0);
        };
        double checksum = 0.0;
        for (Index columns : {Index(64), Index(127), Index(128), Index(63), Index(1), Index(100)}) checksum += pass(columns);  // grows the buffers
        testing::HeapCounter counter;
        for (Index columns : {Index(100), Index(1), Index(128), Index(63), Index(127), Index(64)}) checksum += pass(columns);
        EXPECT_EQ(counter.count(), 0) << (float32 ? "float32" : "double");
        EXPECT_TRUE(std::isfinite(checksum));
    }
}

} // namespace
} // namespace lb::nn
