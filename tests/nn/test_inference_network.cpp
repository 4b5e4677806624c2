#include <gtest/gtest.h>

#include <omp.h>

#include <cmath>
#include <cstdio>

#include "nn/batch_norm.hpp"
#include "nn/inference_network.hpp"
#include "nn/linear.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "nn/weight_format.hpp"
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

// ---- reduced-precision weights ---------------------------------------------------------

/// evaluate() recomputed in double from the network's own ops (the folded float32
/// parameters), with the weights `format` stores (dequantised: W rounded to half, or
/// s_i q(i, j)), and a bound on how far the float32 evaluation may be from it.
///
/// The bound is a first-order forward error analysis of float32 arithmetic, u = 2⁻²⁴,
/// γ_k = k u / (1 − k u), propagating e (a bound on each buffer's error) op by op:
///   affine  y_i = b_i (+ y_i) + Σ_j Ŵ_ij x_j, computed as n FMAs onto the bias (and the
///           accumulated y), int8 one more FMA for the row scale: at most n + 2 roundings, so
///           e(y_i) ≤ γ_{n+2} (|b_i| + |y_i| + Σ_j |Ŵ_ij| |x_j|) + Σ_j |Ŵ_ij| e(x_j) (+ e(y_i));
///   scale   e ≤ γ_2 (|s x| + |t|) + |s| e(x);   add  e ≤ u |dst + src| + e(dst) + e(src);
///   act     e ≤ L e(pre) + 8 u |f(pre)|, L = max |f'| (swish 1.0998, tanh and relu 1), the
///           8 u covering exp, the add and the division of swish (a few ulps).
/// The input is the same float vector in both, so e = 0 there. Products of errors are
/// second order and left out; the check multiplies the bound by 1.001.
struct Reference {
    VectorXd y, bound;
};

double activation_lipschitz(ActivationKind kind) { return kind == ActivationKind::swish ? 1.0998 : 1.0; }

Reference reference_evaluate(const InferenceNetwork& net, const VectorXf& x, WeightFormat format)
{
    constexpr double u = 0x1p-24;
    auto gamma = [&](Index k) { return double(k) * u / (1.0 - double(k) * u); };
    int buffers = 1;
    for (const auto& op : net.ops()) buffers = std::max({buffers, op.src + 1, op.dst + 1});
    const auto n_buffers = static_cast<std::size_t>(buffers);
    std::vector<VectorXd> v(n_buffers), e(n_buffers);
    v[0] = x.cast<double>();
    e[0] = VectorXd::Zero(x.size());
    for (const auto& op : net.ops()) {
        const VectorXd& xs = v[std::size_t(op.src)];
        const VectorXd& es = e[std::size_t(op.src)];
        VectorXd& y = v[std::size_t(op.dst)];
        VectorXd& ey = e[std::size_t(op.dst)];
        const bool has_b = op.kind == InferenceOpKind::affine || op.kind == InferenceOpKind::scale;
        const VectorXd b = has_b ? VectorXd(op.b.head(op.out).cast<double>()) : VectorXd();
        switch (op.kind) {
        case InferenceOpKind::affine: {
            const MatrixXd W = dequantized(op.W, format);
            const VectorXd prev = op.accumulate ? y : VectorXd::Zero(op.out);
            const VectorXd prev_e = op.accumulate ? ey : VectorXd::Zero(op.out);
            y = W * xs + b + prev;
            ey = gamma(op.in + 2) * (b.cwiseAbs() + prev.cwiseAbs() + W.cwiseAbs() * xs.cwiseAbs()) +
                 W.cwiseAbs() * es + prev_e;
            break;
        }
        case InferenceOpKind::scale: {
            const VectorXd t = op.t.cast<double>();
            y = b.cwiseProduct(xs) + t;
            ey = gamma(2) * (b.cwiseProduct(xs).cwiseAbs() + t.cwiseAbs()) + b.cwiseAbs().cwiseProduct(es);
            break;
        }
        case InferenceOpKind::act:
            y = xs;
            ey = es;
            break;
        case InferenceOpKind::add:
            y += xs;
            ey += es + u * y.cwiseAbs();
            break;
        }
        if (op.act != ActivationKind::identity) {
            for (Index i = 0; i < y.size(); ++i) {
                y[i] = activation_value(op.act, y[i]);
                ey[i] = activation_lipschitz(op.act) * ey[i] + 8 * u * std::abs(y[i]);
            }
        }
    }
    const int out = net.ops().back().dst;  // the last op writes the output buffer
    return {v[std::size_t(out)], e[std::size_t(out)]};
}

/// max_i |a_i − ref_i| / bound_i
double worst_bound_ratio(const VectorXd& a, const Reference& ref)
{
    return ((a - ref.y).cwiseAbs().array() / ref.bound.array().max(1e-300)).maxCoeff();
}

struct FormatTestNetwork {
    std::string name;
    InferenceNetwork net;
    bool tight = true;  ///< the bound is tight enough to tell reduced weights from float32 ones
};

/// The armadillo's Table 2 decoder (BatchNorm statistics randomised) and integrator, with a
/// random input standardizer for the integrator.
struct Table2Networks {
    Sequential decoder, integrator;
    Standardizer standardizer;
};
Table2Networks armadillo_networks(Rng& rng)
{
    const auto arch = table2_architecture("armadillo");
    Table2Networks nets;
    nets.decoder = make_mlp(arch.decoder, rng);
    test::randomize_batch_norm(nets.decoder, rng);
    nets.integrator = make_mlp(arch.integrator, rng);
    nets.standardizer = Standardizer(rng.uniform_vector(arch.integrator.in_dim, -1, 1),
                                     rng.uniform_vector(arch.integrator.in_dim, 0.5, 2));
    return nets;
}

/// The armadillo's Table 2 networks (the largest) whole, each of their affine ops alone (a
/// one-Linear network with the op's folded weights, bias and activation), a small random
/// MLP whose sizes are not whole panels, and a network with every op kind (scale, act, add,
/// accumulating projections, tanh and relu). The worst-case bound grows like the product of
/// the layers' ‖|W|‖∞ (about 7 per armadillo layer, 9 layers), far above the actual error
/// (a random walk): whole, the armadillo networks check only that the bound holds; the
/// ops alone and the (narrow) every-op network also check that it is tight enough to fail.
std::vector<FormatTestNetwork> format_test_networks(Rng& rng, WeightFormat format)
{
    std::vector<FormatTestNetwork> nets;
    const auto arch = table2_architecture("armadillo");
    const auto [decoder, integrator, standardizer] = armadillo_networks(rng);
    nets.push_back({"armadillo decoder", InferenceNetwork(decoder, nullptr, format), false});
    nets.push_back({"armadillo integrator", InferenceNetwork(integrator, &standardizer, format), false});
    for (std::size_t n = 0; n < 2; ++n) {
        const InferenceNetwork whole = nets[n].net;
        for (std::size_t k = 0; k < whole.ops().size(); ++k) {
            const auto& op = whole.ops()[k];
            if (op.kind != InferenceOpKind::affine) continue;
            Sequential one;
            auto& lin = one.emplace<Linear>(op.in, op.out);
            lin.weight() = op.W.cast<double>();
            lin.bias() = op.b.head(op.out).cast<double>();
            if (op.act != ActivationKind::identity) one.emplace<Activation>(op.act);
            nets.push_back({nets[n].name + " op " + std::to_string(k) + " " + std::to_string(op.in) + "->" +
                                std::to_string(op.out),
                            InferenceNetwork(one, nullptr, format)});
        }
    }
    MlpSpec s;
    s.in_dim = 9;
    s.hidden = {70, 130};
    s.out_dim = 67;  // neither a whole panel nor one
    nets.push_back({"mlp 9-70-130-67", InferenceNetwork(make_mlp(s, rng), nullptr, format), false});  // 3 layers: too loose
    Sequential every_op = unfoldable_network(rng, true);
    test::randomize_batch_norm(every_op, rng);
    nets.push_back({"every op kind", InferenceNetwork(every_op, nullptr, format)});
    return nets;
}

TEST(InferenceNetwork, ReducedWeightsMatchADoubleReferenceOfTheDequantisedWeights)
{
    for (WeightFormat format : {WeightFormat::f32, WeightFormat::f16, WeightFormat::int8}) {
        Rng rng(91);
        for (auto& [name, net, tight] : format_test_networks(rng, format)) {
            ASSERT_EQ(net.weight_format(), format);
            double worst = 0.0, worst_undequantised = 0.0;
            for (int trial = 0; trial < 3; ++trial) {
                const VectorXf x = test::random_matrix(net.in_features(), 1, rng, -2, 2).col(0).cast<float>();
                const VectorXd y = net.evaluate(x).cast<double>();
                const Reference ref = reference_evaluate(net, x, format);
                ASSERT_EQ(ref.y.size(), net.out_features()) << name;
                worst = std::max(worst, worst_bound_ratio(y, ref));
                // The same reference from the float32 weights: reduced weights must land outside
                // its bound, or this test could not tell whether they are used at all.
                worst_undequantised =
                    std::max(worst_undequantised, worst_bound_ratio(y, reference_evaluate(net, x, WeightFormat::f32)));
            }
            std::printf("[ weights ] %-5s %-42s |error| / bound %.2g (against the f32 weights' reference: %.3g)\n",
                        to_string(format).c_str(), name.c_str(), worst, worst_undequantised);
            EXPECT_LE(worst, 1.001) << to_string(format) << ", " << name;
            if (format != WeightFormat::f32 && tight) {
                EXPECT_GT(worst_undequantised, 1.001) << to_string(format) << ", " << name;
            }
        }
    }
}

/// ‖y − y_f32‖∞ / ‖y_f32‖∞ of the armadillo networks, printed; the bounds are loose (about
/// 10× the measured values) but far below what a wrong panel offset or a lost row scale give
/// (errors of order 1).
TEST(InferenceNetwork, ReducedWeightsStayCloseToFloat32)
{
    const std::vector<std::pair<WeightFormat, double>> limits = {{WeightFormat::f16, 3e-3}, {WeightFormat::int8, 5e-2}};
    Rng rng(92);
    const auto arch = table2_architecture("armadillo");
    const auto [decoder, integrator, standardizer] = armadillo_networks(rng);
    InferenceNetwork dec32(decoder), int32(integrator, &standardizer);
    for (const auto& [format, limit] : limits) {
        InferenceNetwork dec(decoder, nullptr, format), integ(integrator, &standardizer, format);
        double dec_error = 0.0, int_error = 0.0;
        for (int trial = 0; trial < 5; ++trial) {
            const VectorXf q = test::random_matrix(arch.integrator.in_dim, 1, rng, -2, 2).col(0).cast<float>();
            const VectorXd z32 = int32.evaluate(q).cast<double>();
            int_error = std::max(int_error, relative_error(integ.evaluate(q).cast<double>(), z32));
            const VectorXf z = z32.cast<float>();
            const VectorXd x32 = dec32.evaluate(z).cast<double>();
            dec_error = std::max(dec_error, relative_error(dec.evaluate(z).cast<double>(), x32));
        }
        std::printf("[ weights ] %-5s armadillo relative error against f32: integrator %.3g, decoder %.3g (limit %.0e)\n",
                    to_string(format).c_str(), int_error, dec_error, limit);
        EXPECT_LT(int_error, limit) << to_string(format);
        EXPECT_LT(dec_error, limit) << to_string(format);
        EXPECT_GT(dec_error, 0.0) << to_string(format) << ": the weights were not reduced";
    }
}

TEST(InferenceNetwork, Int8RowOfZerosGivesTheBias)
{
    Rng rng(93);
    Sequential net;
    auto& lin = net.emplace<Linear>(5, 70, rng);  // two panels
    lin.bias() = test::random_matrix(70, 1, rng, -3, 3).col(0);
    for (Index row : {Index(3), Index(66)}) lin.weight().row(row).setZero();
    InferenceNetwork fast(net, nullptr, WeightFormat::int8);
    const VectorXf x = test::random_matrix(5, 1, rng, -2, 2).col(0).cast<float>();
    const VectorXf y = fast.evaluate(x);
    for (Index row : {Index(3), Index(66)}) EXPECT_EQ(y[row], float(lin.bias()[row])) << "row " << row;
    EXPECT_EQ(fast.ops().back().row_scale[3], 1.0f);
    EXPECT_NE(y[4], float(lin.bias()[4]));
}

TEST(InferenceNetwork, WeightFormatSwitchesAndLeavesFloat32AndDerivativesAlone)
{
    Rng rng(94);
    Sequential net = make_mlp(table2_architecture("cloth").decoder, rng);
    test::randomize_batch_norm(net, rng);
    InferenceNetwork f32(net);
    InferenceNetwork fmt(net);
    const VectorXf z = test::random_matrix(f32.in_features(), 1, rng, -1, 1).col(0).cast<float>();
    const VectorXf y32 = f32.evaluate(z);
    const std::vector<Index> rows = {30, 31, 32};
    MatrixXf J32(3, f32.in_features()), J(3, f32.in_features());
    f32.jacobian_rows(z, rows, J32);
    const MatrixXf Z = test::random_matrix(f32.in_features(), 5, rng, -1, 1).cast<float>();
    const MatrixXf Y32 = f32.forward_batch(Z);
    for (WeightFormat format : {WeightFormat::f16, WeightFormat::int8, WeightFormat::f32}) {
        fmt.set_weight_format(format);
        EXPECT_EQ(fmt.describe().rfind("weights " + to_string(format) + "\n", 0), 0u) << fmt.describe();
        const VectorXf y = fmt.evaluate(z);
        if (format == WeightFormat::f32)
            EXPECT_TRUE((y.array() == y32.array()).all()) << "f32 after a round trip through the other formats";
        else
            EXPECT_FALSE((y.array() == y32.array()).all()) << to_string(format);
        fmt.jacobian_rows(z, rows, J);
        EXPECT_TRUE((J.array() == J32.array()).all()) << to_string(format) << ": jacobian_rows uses the f32 weights";
        const MatrixXf Y = fmt.forward_batch(Z);
        EXPECT_TRUE((Y.array() == Y32.array()).all()) << to_string(format) << ": forward_batch uses the f32 weights";
    }
    InferenceNetwork explicit_f32(net, nullptr, WeightFormat::f32);
    EXPECT_TRUE((explicit_f32.evaluate(z).array() == y32.array()).all());

    // Bytes streamed: halves are half the floats; int8 a quarter, plus one float scale per padded row.
    const long long bytes32 = f32.weight_bytes();
    long long padded_rows = 0;
    for (const auto& op : f32.ops())
        if (op.kind == InferenceOpKind::affine) padded_rows += op.b.size();
    fmt.set_weight_format(WeightFormat::f16);
    EXPECT_EQ(fmt.weight_bytes() * 2, bytes32);
    fmt.set_weight_format(WeightFormat::int8);
    EXPECT_EQ(fmt.weight_bytes(), bytes32 / 4 + padded_rows * 4);
    EXPECT_EQ(fmt.multiply_adds(), f32.multiply_adds());

    InferenceNetworkD d(net);
    EXPECT_THROW(d.set_weight_format(WeightFormat::f16), std::invalid_argument);
    EXPECT_EQ(d.describe().rfind("weights f64\n", 0), 0u);
}

TEST(InferenceNetwork, EvaluateAndJacobianRowsDoNotAllocate)
{
    if (!testing::heap_counting_available()) GTEST_SKIP() << "heap counting needs glibc without AddressSanitizer";
    for (WeightFormat format : {WeightFormat::f32, WeightFormat::f16, WeightFormat::int8}) {
        SCOPED_TRACE("weights " + to_string(format));
        Rng rng(85);
        const auto arch = table2_architecture("armadillo");
        Sequential decoder = make_mlp(arch.decoder, rng);
        Sequential integrator = make_mlp(arch.integrator, rng);
        const Standardizer standardizer(arch.integrator.in_dim);
        InferenceNetwork dec(decoder, nullptr, format);
        InferenceNetwork integ(integrator, &standardizer, format);
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
