// Per-frame inference latency of the paper's Table 2 networks (batch 1, one thread):
//   nn/frame/<precision>/<example>   integrator + decoder, the "Ours" column
//   nn/integrate|decode/float/<ex>   the two halves (Table 1 columns)
//   nn/gemv_bound/<kernel>/<ex>      only the matrix-vector products over the same
//                                    weights (no bias, activation or adds): a lower bound
//   nn/jvp_vertex/<precision>/<ex>   Jacobian of one vertex's 3 outputs w.r.t. the
//                                    latent (Table 2 "Computing Jvp")
// precision: float = InferenceNetwork, double = InferenceNetworkD (same fused ops),
// double_sequential = the training-path Sequential::forward in eval mode; f16 / int8 =
// InferenceNetwork streaming half or int8 weights (nn/weight_format.hpp), float32
// accumulation. gemv_bound kernels: packed_float, packed_f16, packed_int8 (the
// InferenceNetwork's gemv_only() in that format; int8 includes its row scales) and
// eigen_float (Eigen's GEMV on plain copies).
// Architectures: paper/paper_architectures.hpp (decoder: residual blocks + BatchNorm +
// Swish, PCA layer 50 -> DOF; integrator: Swish MLP with input 2·latent + 3·p).
// Counters: madds = multiply-adds per frame, weight_GBps = packed weight bytes
// streamed per second.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

#include "nn/inference_network.hpp"
#include "nn/mlp_spec.hpp"
#include "nn/network_derivatives.hpp"
#include "paper/paper_architectures.hpp"

namespace {

using namespace lb;
using namespace lb::nn;

struct Models {
    PaperArchitecture arch;
    Sequential decoder, integrator;
    Standardizer standardizer;
    InferenceNetwork decoder_f, integrator_f;
    InferenceNetwork decoder_f16, integrator_f16, decoder_int8, integrator_int8;
    InferenceNetworkD decoder_d, integrator_d;
    std::vector<MatrixXf> weights_f;  ///< plain column-major copies of every affine weight
    VectorXf q_f;
    VectorXd q_d;
    std::vector<Index> vertex;
};

/// Networks with random (PyTorch-default) weights and non-trivial BatchNorm statistics.
Models& models(const std::string& name)
{
    static std::map<std::string, std::unique_ptr<Models>> cache;
    auto& slot = cache[name];
    if (slot) return *slot;
    slot = std::make_unique<Models>();
    Models& m = *slot;
    m.arch = table2_architecture(name);
    Rng rng(2025);
    m.decoder = make_mlp(m.arch.decoder, rng);
    m.integrator = make_mlp(m.arch.integrator, rng);
    for (auto& b : m.decoder.buffers()) {
        if (b.integer) continue;
        for (Index i = 0; i < b.value.rows(); ++i)
            b.value(i, 0) = b.name.find("running_var") != std::string::npos ? rng.uniform(0.5, 2.0) : rng.uniform(-0.1, 0.1);
    }
    m.standardizer = Standardizer(rng.uniform_vector(m.arch.integrator.in_dim, -1, 1),
                                  rng.uniform_vector(m.arch.integrator.in_dim, 0.5, 2));
    m.decoder_f = InferenceNetwork(m.decoder);
    m.integrator_f = InferenceNetwork(m.integrator, &m.standardizer);
    m.decoder_f16 = InferenceNetwork(m.decoder, nullptr, WeightFormat::f16);
    m.integrator_f16 = InferenceNetwork(m.integrator, &m.standardizer, WeightFormat::f16);
    m.decoder_int8 = InferenceNetwork(m.decoder, nullptr, WeightFormat::int8);
    m.integrator_int8 = InferenceNetwork(m.integrator, &m.standardizer, WeightFormat::int8);
    m.decoder_d = InferenceNetworkD(m.decoder);
    m.integrator_d = InferenceNetworkD(m.integrator, &m.standardizer);
    for (const auto* net : {&m.integrator_f, &m.decoder_f})
        for (const auto& op : net->ops())
            if (op.kind == InferenceOpKind::affine) m.weights_f.push_back(op.W);
    m.q_d = rng.uniform_vector(m.arch.integrator.in_dim, -1, 1);
    m.q_f = m.q_d.cast<float>();
    const Index v = m.arch.full_dof / 3 / 2;  // a vertex in the middle
    m.vertex = {3 * v, 3 * v + 1, 3 * v + 2};
    return m;
}

void set_counters(benchmark::State& state, long long madds, long long bytes)
{
    state.counters["madds"] = static_cast<double>(madds);
    state.counters["weight_GBps"] =
        benchmark::Counter(static_cast<double>(bytes) * 1e-9, benchmark::Counter::kIsIterationInvariantRate);
}

void frame_float(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    VectorXf z(m.arch.latent_dim), x(m.arch.full_dof);
    for (auto _ : state) {
        m.integrator_f.evaluate(m.q_f.data(), z.data());
        m.decoder_f.evaluate(z.data(), x.data());
        benchmark::DoNotOptimize(x.data());
        benchmark::ClobberMemory();
    }
    set_counters(state, m.integrator_f.multiply_adds() + m.decoder_f.multiply_adds(),
                 m.integrator_f.weight_bytes() + m.decoder_f.weight_bytes());
}

/// The (integrator, decoder) pair streaming weights in `format`.
std::pair<InferenceNetwork*, InferenceNetwork*> networks(Models& m, WeightFormat format)
{
    switch (format) {
    case WeightFormat::f16: return {&m.integrator_f16, &m.decoder_f16};
    case WeightFormat::int8: return {&m.integrator_int8, &m.decoder_int8};
    case WeightFormat::f32: break;
    }
    return {&m.integrator_f, &m.decoder_f};
}

void frame_reduced(benchmark::State& state, const std::string& name, WeightFormat format)
{
    Models& m = models(name);
    auto [integrator, decoder] = networks(m, format);
    VectorXf z(m.arch.latent_dim), x(m.arch.full_dof);
    for (auto _ : state) {
        integrator->evaluate(m.q_f.data(), z.data());
        decoder->evaluate(z.data(), x.data());
        benchmark::DoNotOptimize(x.data());
        benchmark::ClobberMemory();
    }
    set_counters(state, integrator->multiply_adds() + decoder->multiply_adds(),
                 integrator->weight_bytes() + decoder->weight_bytes());
}

void frame_f16(benchmark::State& state, std::string name) { frame_reduced(state, name, WeightFormat::f16); }
void frame_int8(benchmark::State& state, std::string name) { frame_reduced(state, name, WeightFormat::int8); }

void frame_double(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    VectorXd z(m.arch.latent_dim), x(m.arch.full_dof);
    for (auto _ : state) {
        m.integrator_d.evaluate(m.q_d.data(), z.data());
        m.decoder_d.evaluate(z.data(), x.data());
        benchmark::DoNotOptimize(x.data());
        benchmark::ClobberMemory();
    }
    set_counters(state, m.integrator_d.multiply_adds() + m.decoder_d.multiply_adds(),
                 m.integrator_d.weight_bytes() + m.decoder_d.weight_bytes());
}

void frame_double_sequential(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    for (auto _ : state) {
        const MatrixXd z = m.integrator.forward(m.standardizer.apply(m.q_d), false);
        const MatrixXd x = m.decoder.forward(z, false);
        benchmark::DoNotOptimize(x.data());
    }
}

void integrate_float(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    VectorXf z(m.arch.latent_dim);
    for (auto _ : state) {
        m.integrator_f.evaluate(m.q_f.data(), z.data());
        benchmark::DoNotOptimize(z.data());
        benchmark::ClobberMemory();
    }
    set_counters(state, m.integrator_f.multiply_adds(), m.integrator_f.weight_bytes());
}

void decode_float(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    const VectorXf z = m.integrator_f.evaluate(m.q_f);
    VectorXf x(m.arch.full_dof);
    for (auto _ : state) {
        m.decoder_f.evaluate(z.data(), x.data());
        benchmark::DoNotOptimize(x.data());
        benchmark::ClobberMemory();
    }
    set_counters(state, m.decoder_f.multiply_adds(), m.decoder_f.weight_bytes());
}

void gemv_bound_packed(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    for (auto _ : state) {
        m.integrator_f.gemv_only();
        m.decoder_f.gemv_only();
        benchmark::ClobberMemory();
    }
    set_counters(state, m.integrator_f.multiply_adds() + m.decoder_f.multiply_adds(),
                 m.integrator_f.weight_bytes() + m.decoder_f.weight_bytes());
}

void gemv_bound_reduced(benchmark::State& state, const std::string& name, WeightFormat format)
{
    Models& m = models(name);
    auto [integrator, decoder] = networks(m, format);
    for (auto _ : state) {
        integrator->gemv_only();
        decoder->gemv_only();
        benchmark::ClobberMemory();
    }
    set_counters(state, integrator->multiply_adds() + decoder->multiply_adds(),
                 integrator->weight_bytes() + decoder->weight_bytes());
}

void gemv_bound_f16(benchmark::State& state, std::string name) { gemv_bound_reduced(state, name, WeightFormat::f16); }
void gemv_bound_int8(benchmark::State& state, std::string name) { gemv_bound_reduced(state, name, WeightFormat::int8); }

void gemv_bound_eigen(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    std::vector<VectorXf> xs, ys;
    long long madds = 0, bytes = 0;
    for (const auto& W : m.weights_f) {
        xs.push_back(VectorXf::Ones(W.cols()));
        ys.push_back(VectorXf::Zero(W.rows()));
        madds += W.size();
        bytes += W.size() * static_cast<long long>(sizeof(float));
    }
    for (auto _ : state) {
        for (std::size_t i = 0; i < m.weights_f.size(); ++i) ys[i].noalias() = m.weights_f[i] * xs[i];
        benchmark::DoNotOptimize(ys.back().data());
        benchmark::ClobberMemory();
    }
    set_counters(state, madds, bytes);
}

void jvp_vertex_float(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    const VectorXf z = m.integrator_f.evaluate(m.q_f);
    MatrixXf J(3, m.arch.latent_dim);
    for (auto _ : state) {
        m.decoder_f.jacobian_rows(z, m.vertex, J);
        benchmark::DoNotOptimize(J.data());
        benchmark::ClobberMemory();
    }
}

void jvp_vertex_double(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    const VectorXd z = m.integrator_d.evaluate(m.q_d);
    MatrixXd J(3, m.arch.latent_dim);
    for (auto _ : state) {
        m.decoder_d.jacobian_rows(z, m.vertex, J);
        benchmark::DoNotOptimize(J.data());
        benchmark::ClobberMemory();
    }
}

void jvp_vertex_double_sequential(benchmark::State& state, std::string name)
{
    Models& m = models(name);
    const VectorXd z = m.integrator_d.evaluate(m.q_d);
    for (auto _ : state) {
        const MatrixXd J = jacobian_rows(m.decoder, z, m.vertex);
        benchmark::DoNotOptimize(J.data());
    }
}

const int registered = [] {
    using Fn = void (*)(benchmark::State&, std::string);
    const std::vector<std::pair<std::string, Fn>> kinds = {
        {"nn/frame/float/", frame_float},
        {"nn/frame/f16/", frame_f16},
        {"nn/frame/int8/", frame_int8},
        {"nn/frame/double/", frame_double},
        {"nn/frame/double_sequential/", frame_double_sequential},
        {"nn/integrate/float/", integrate_float},
        {"nn/decode/float/", decode_float},
        {"nn/gemv_bound/packed_float/", gemv_bound_packed},
        {"nn/gemv_bound/packed_f16/", gemv_bound_f16},
        {"nn/gemv_bound/packed_int8/", gemv_bound_int8},
        {"nn/gemv_bound/eigen_float/", gemv_bound_eigen},
        {"nn/jvp_vertex/float/", jvp_vertex_float},
        {"nn/jvp_vertex/double/", jvp_vertex_double},
        {"nn/jvp_vertex/double_sequential/", jvp_vertex_double_sequential},
    };
    for (const auto& [prefix, fn] : kinds)
        for (const auto& arch : table2_architectures())
            benchmark::RegisterBenchmark((prefix + arch.name).c_str(), fn, arch.name)
                ->Unit(benchmark::kMicrosecond);
    return 0;
}();

} // namespace
