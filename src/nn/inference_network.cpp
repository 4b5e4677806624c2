#include "nn/inference_network.hpp"

#include <algorithm>
#include <cassert>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include <omp.h>

#if defined(__AVX__) && defined(__FMA__)
#include <immintrin.h>
#define LB_NN_AVX_FMA 1
#endif

#include "core/parallel.hpp"
#include "nn/batch_norm.hpp"
#include "nn/half.hpp"
#include "nn/linear.hpp"
#include "nn/residual_block.hpp"

namespace lb::nn {

namespace {

// ---- SIMD abstraction: 8 vectors per panel -------------------------------------------
constexpr int vectors_per_panel = 8;

template <typename S>
struct Simd;

#ifdef LB_NN_AVX_FMA
template <>
struct Simd<float> {
    using V = __m256;
    static constexpr int lanes = 8;
    static V zero() { return _mm256_setzero_ps(); }
    static V set1(float x) { return _mm256_set1_ps(x); }
    static V load(const float* p) { return _mm256_load_ps(p); }
    static V loadu(const float* p) { return _mm256_loadu_ps(p); }
    static void storeu(float* p, V v) { _mm256_storeu_ps(p, v); }
    static V fmadd(V a, V b, V c) { return _mm256_fmadd_ps(a, b, c); }
    static V add(V a, V b) { return _mm256_add_ps(a, b); }
};
template <>
struct Simd<double> {
    using V = __m256d;
    static constexpr int lanes = 4;
    static V zero() { return _mm256_setzero_pd(); }
    static V set1(double x) { return _mm256_set1_pd(x); }
    static V load(const double* p) { return _mm256_load_pd(p); }
    static V loadu(const double* p) { return _mm256_loadu_pd(p); }
    static void storeu(double* p, V v) { _mm256_storeu_pd(p, v); }
    static V fmadd(V a, V b, V c) { return _mm256_fmadd_pd(a, b, c); }
    static V add(V a, V b) { return _mm256_add_pd(a, b); }
};
#else
template <typename S>
struct Simd {
    using V = S;
    static constexpr int lanes = 1;
    static V zero() { return S(0); }
    static V set1(S x) { return x; }
    static V load(const S* p) { return *p; }
    static V loadu(const S* p) { return *p; }
    static void storeu(S* p, V v) { *p = v; }
    static V fmadd(V a, V b, V c) { return a * b + c; }
    static V add(V a, V b) { return a + b; }
};
#endif

template <typename S>
constexpr Index panel_rows()
{
    return Index(Simd<S>::lanes) * vectors_per_panel;
}

template <typename S>
Index padded(Index n)
{
    const Index R = panel_rows<S>();
    return (n + R - 1) / R * R;
}

/// y[0, P·R) (=|+=) packed · x (+ bias). `packed` holds P panels of in × R.
template <typename S>
void packed_gemv(const S* packed, const S* bias, const S* x, Index in, Index panels, S* y, bool accumulate)
{
    using Ops = Simd<S>;
    using V = typename Ops::V;
    constexpr int L = Ops::lanes;
    constexpr Index R = panel_rows<S>();
    for (Index p = 0; p < panels; ++p) {
        const S* P = packed + p * in * R;
        S* yp = y + p * R;
        V acc[vectors_per_panel];
        for (int v = 0; v < vectors_per_panel; ++v) {
            V init = bias ? Ops::loadu(bias + p * R + v * L) : Ops::zero();
            if (accumulate) init = Ops::add(init, Ops::loadu(yp + v * L));
            acc[v] = init;
        }
        for (Index j = 0; j < in; ++j) {
            const V xj = Ops::set1(x[j]);
            const S* col = P + j * R;
            for (int v = 0; v < vectors_per_panel; ++v) acc[v] = Ops::fmadd(Ops::load(col + v * L), xj, acc[v]);
        }
        for (int v = 0; v < vectors_per_panel; ++v) Ops::storeu(yp + v * L, acc[v]);
    }
}

// ---- reduced-precision weights (float network) -----------------------------------------
/// L consecutive stored weights as a float vector: halves (F16C), int8 (AVX2), or their
/// scalar conversions where the instructions are not compiled in.
inline Simd<float>::V load_weights(const std::uint16_t* p)
{
#if defined(LB_NN_AVX_FMA) && defined(__F16C__)
    return _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p)));
#elif defined(LB_NN_AVX_FMA)
    return _mm256_setr_ps(half_to_float(p[0]), half_to_float(p[1]), half_to_float(p[2]), half_to_float(p[3]),
                          half_to_float(p[4]), half_to_float(p[5]), half_to_float(p[6]), half_to_float(p[7]));
#else
    return half_to_float(*p);
#endif
}

inline Simd<float>::V load_weights(const std::int8_t* p)
{
#if defined(LB_NN_AVX_FMA) && defined(__AVX2__)
    return _mm256_cvtepi32_ps(_mm256_cvtepi8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))));
#elif defined(LB_NN_AVX_FMA)
    return _mm256_setr_ps(float(p[0]), float(p[1]), float(p[2]), float(p[3]), float(p[4]), float(p[5]), float(p[6]),
                          float(p[7]));
#else
    return float(*p);
#endif
}

/// packed_gemv<float> for weights stored as W (halves or int8) in the same panels. int8:
/// the products q · x are accumulated from zero, then y = s ⊙ acc + bias (+ y) with one
/// FMA per vector (`row_scale` padded as y); halves: as the float kernel.
template <typename W>
void packed_gemv_reduced(const W* packed, const float* row_scale, const float* bias, const float* x, Index in,
                         Index panels, float* y, bool accumulate)
{
    using Ops = Simd<float>;
    using V = Ops::V;
    constexpr int L = Ops::lanes;
    constexpr Index R = panel_rows<float>();
    constexpr bool scaled = std::is_same_v<W, std::int8_t>;
    for (Index p = 0; p < panels; ++p) {
        const W* P = packed + p * in * R;
        float* yp = y + p * R;
        V init[vectors_per_panel], acc[vectors_per_panel];
        for (int v = 0; v < vectors_per_panel; ++v) {
            init[v] = bias ? Ops::loadu(bias + p * R + v * L) : Ops::zero();
            if (accumulate) init[v] = Ops::add(init[v], Ops::loadu(yp + v * L));
            acc[v] = scaled ? Ops::zero() : init[v];
        }
        for (Index j = 0; j < in; ++j) {
            const V xj = Ops::set1(x[j]);
            const W* col = P + j * R;
            for (int v = 0; v < vectors_per_panel; ++v) acc[v] = Ops::fmadd(load_weights(col + v * L), xj, acc[v]);
        }
        for (int v = 0; v < vectors_per_panel; ++v) {
            if constexpr (scaled) acc[v] = Ops::fmadd(acc[v], Ops::loadu(row_scale + p * R + v * L), init[v]);
            Ops::storeu(yp + v * L, acc[v]);
        }
    }
}

/// Copy `out` × `in` values into panels of R rows (column j of panel p at (p·in + j)·R),
/// zero-padded: the layout of every packed_gemv kernel.
template <typename T, typename Get>
void pack_panels(std::vector<T, Eigen::aligned_allocator<T>>& packed, Index out, Index in, Index R, Get get)
{
    const Index panels = (out + R - 1) / R;
    packed.assign(static_cast<std::size_t>(panels * in * R), T(0));
    for (Index p = 0; p < panels; ++p)
        for (Index j = 0; j < in; ++j)
            for (Index i = 0; i < R && p * R + i < out; ++i)
                packed[static_cast<std::size_t>((p * in + j) * R + i)] = get(p * R + i, j);
}

/// Rows of a panel of the transposed weights used by the reverse-mode kernel.
constexpr int transposed_vectors_per_panel = 4;
template <typename S>
constexpr Index transposed_panel_rows()
{
    return Index(Simd<S>::lanes) * transposed_vectors_per_panel;
}

/// Y[:, c] += Wᵀ A[:, c] for KC columns, with Wᵀ packed in panels of RT rows (input
/// features): panel p holds, for every output i, the RT weights W(i, pRT .. pRT+RT)
/// contiguously. Each weight vector is loaded once and used for all KC columns.
/// Y must have panels·RT rows (padded); A holds `out` rows.
template <typename S, int KC>
void packed_transpose_product(const S* packed_t, Index out, Index panels, const S* A, Index lda, S* Y, Index ldy)
{
    using Ops = Simd<S>;
    using V = typename Ops::V;
    constexpr int L = Ops::lanes;
    constexpr int NV = transposed_vectors_per_panel;
    constexpr Index RT = transposed_panel_rows<S>();
    for (Index p = 0; p < panels; ++p) {
        V acc[KC][NV];
        for (int c = 0; c < KC; ++c)
            for (int v = 0; v < NV; ++v) acc[c][v] = Ops::loadu(Y + c * ldy + p * RT + v * L);
        const S* P = packed_t + p * out * RT;
        for (Index i = 0; i < out; ++i) {
            V w[NV];
            for (int v = 0; v < NV; ++v) w[v] = Ops::load(P + i * RT + v * L);
            for (int c = 0; c < KC; ++c) {
                const V a = Ops::set1(A[c * lda + i]);
                for (int v = 0; v < NV; ++v) acc[c][v] = Ops::fmadd(w[v], a, acc[c][v]);
            }
        }
        for (int c = 0; c < KC; ++c)
            for (int v = 0; v < NV; ++v) Ops::storeu(Y + c * ldy + p * RT + v * L, acc[c][v]);
    }
}

// ---- compilation in double precision ---------------------------------------------------
struct DoubleOp {
    using Kind = InferenceOpKind;
    Kind kind = Kind::affine;
    int src = -1, dst = -1;
    bool accumulate = false;
    ActivationKind act = ActivationKind::identity;
    MatrixXd W;
    VectorXd b, t;  // affine: bias; scale: s (in b) and t
};

class Compiler {
public:
    std::vector<DoubleOp> ops;
    std::vector<Index> sizes;
    std::vector<bool> read;

    int new_buffer(Index size)
    {
        sizes.push_back(size);
        read.push_back(false);
        return static_cast<int>(sizes.size()) - 1;
    }

    void emit(DoubleOp op)
    {
        read[static_cast<std::size_t>(op.src)] = true;
        ops.push_back(std::move(op));
    }

    int scale(int src, const VectorXd& s, const VectorXd& t)
    {
        DoubleOp op;
        op.kind = DoubleOp::Kind::scale;
        op.src = src;
        op.dst = new_buffer(sizes[static_cast<std::size_t>(src)]);
        op.b = s;
        op.t = t;
        const int dst = op.dst;
        emit(std::move(op));
        return dst;
    }

    /// Fold y ← s ⊙ y + t into the affine ops that produce buffer `buf`, if possible.
    bool fold_scale_backward(int buf, const VectorXd& s, const VectorXd& t)
    {
        if (read[static_cast<std::size_t>(buf)]) return false;
        std::vector<std::size_t> chain;
        for (std::size_t i = ops.size(); i-- > 0;) {
            const DoubleOp& op = ops[i];
            if (op.dst != buf || op.kind != DoubleOp::Kind::affine || op.act != ActivationKind::identity) return false;
            chain.push_back(i);
            if (!op.accumulate) break;
            if (i == 0) return false;
        }
        if (chain.empty() || ops[chain.back()].accumulate) return false;
        for (std::size_t i : chain) {
            DoubleOp& op = ops[i];
            op.W = s.asDiagonal() * op.W;
            op.b = s.cwiseProduct(op.b);
            if (!op.accumulate) op.b += t;
        }
        return true;
    }

    int compile(const Layer& layer, int src)
    {
        const Index n = sizes[static_cast<std::size_t>(src)];
        if (layer.in_features() != 0 && layer.in_features() != n)
            throw std::invalid_argument("InferenceNetwork: " + layer.type_name() + " expects " +
                                        std::to_string(layer.in_features()) + " inputs, got " + std::to_string(n));
        if (const auto* seq = dynamic_cast<const Sequential*>(&layer)) {
            int cur = src;
            for (Index i = 0; i < seq->size(); ++i) cur = compile(seq->layer(i), cur);
            return cur;
        }
        if (const auto* lin = dynamic_cast<const Linear*>(&layer)) {
            DoubleOp op;
            op.kind = DoubleOp::Kind::affine;
            op.src = src;
            op.dst = new_buffer(lin->out_features());
            op.W = lin->weight();
            op.b = lin->bias();
            const int dst = op.dst;
            emit(std::move(op));
            return dst;
        }
        if (const auto* bn = dynamic_cast<const BatchNorm1d*>(&layer)) {
            const VectorXd s = bn->eval_scale(), t = bn->eval_shift();
            if (fold_scale_backward(src, s, t)) return src;
            return scale(src, s, t);
        }
        if (const auto* act = dynamic_cast<const Activation*>(&layer)) {
            if (act->kind() == ActivationKind::identity) return src;
            if (!ops.empty() && !read[static_cast<std::size_t>(src)]) {
                DoubleOp& last = ops.back();
                if (last.dst == src && last.kind == DoubleOp::Kind::affine && last.act == ActivationKind::identity) {
                    last.act = act->kind();
                    return src;
                }
            }
            DoubleOp op;
            op.kind = DoubleOp::Kind::act;
            op.src = src;
            op.dst = new_buffer(n);
            op.act = act->kind();
            const int dst = op.dst;
            emit(std::move(op));
            return dst;
        }
        if (const auto* res = dynamic_cast<const ResidualBlock*>(&layer)) {
            const int y = compile(res->f(), src);
            if (y == src) throw std::invalid_argument("InferenceNetwork: residual block with an identity body");
            DoubleOp op;
            op.src = src;
            op.dst = y;
            if (res->has_projection()) {
                op.kind = DoubleOp::Kind::affine;
                op.accumulate = true;
                op.W = res->projection().weight();
                op.b = res->projection().bias();
            } else {
                op.kind = DoubleOp::Kind::add;
            }
            emit(std::move(op));
            return y;
        }
        throw std::invalid_argument("InferenceNetwork: unsupported layer type " + layer.type_name());
    }

    /// Fold scale ops whose output only feeds affine ops into those ops' weights.
    void fold_scales_forward(int output)
    {
        for (std::size_t i = 0; i < ops.size();) {
            const DoubleOp& s_op = ops[i];
            bool foldable = s_op.kind == DoubleOp::Kind::scale && s_op.dst != output;
            std::vector<std::size_t> readers;
            for (std::size_t k = 0; foldable && k < ops.size(); ++k) {
                if (k == i) continue;
                if (ops[k].dst == s_op.dst) foldable = false;
                if (ops[k].src == s_op.dst) {
                    if (ops[k].kind != DoubleOp::Kind::affine) foldable = false;
                    readers.push_back(k);
                }
            }
            // s_op.src must not change between the scale and its readers.
            for (std::size_t r : readers)
                for (std::size_t k = i + 1; foldable && k < r; ++k)
                    if (ops[k].dst == s_op.src) foldable = false;
            if (!foldable || readers.empty()) {
                ++i;
                continue;
            }
            for (std::size_t r : readers) {
                DoubleOp& op = ops[r];
                op.b += op.W * s_op.t;
                op.W = op.W * s_op.b.asDiagonal();
                op.src = s_op.src;
            }
            ops.erase(ops.begin() + static_cast<std::ptrdiff_t>(i));
        }
    }
};

template <typename S>
Eigen::Matrix<S, Eigen::Dynamic, 1> padded_vector(const VectorXd& v)
{
    Eigen::Matrix<S, Eigen::Dynamic, 1> out = Eigen::Matrix<S, Eigen::Dynamic, 1>::Zero(padded<S>(v.size()));
    out.head(v.size()) = v.cast<S>();
    return out;
}

/// Row-wise scaling M.row(r) *= act'(pre[r]).
template <typename M, typename Vec>
void scale_rows_by_derivative(ActivationKind kind, const Vec& pre, M&& m)
{
    if (kind == ActivationKind::identity) return;
    for (Index r = 0; r < m.rows(); ++r) m.row(r) *= activation_derivative(kind, pre[r]);
}

/// The batched forward's activation with its tape: a ← f(a) and d ← f'(a) element-wise
/// (arrays of the same shape), vectorised, one exponential per element for Swish (the
/// reverse pass then multiplies by d). The same expressions as apply_activation and
/// f' = σ(1 + a(1 − σ)), so the values equal those computed separately.
template <typename A, typename D>
void activate_with_derivative(ActivationKind kind, A&& a, D&& d, GrowingMatrix<typename std::decay_t<A>::Scalar>& scratch)
{
    using S = typename std::decay_t<A>::Scalar;
    switch (kind) {
    case ActivationKind::swish: {
        // 1 + e^{-a} kept in `scratch` (an evaluated temporary would be allocated per call).
        auto denominator = scratch.resize(a.rows(), a.cols()).array();
        denominator = S(1) + (-a).exp();
        const auto sigma = denominator.inverse();
        d = sigma * (S(1) + a * (S(1) - sigma));
        a = a / denominator;
        break;
    }
    case ActivationKind::tanh:
        a = a.tanh();
        d = S(1) - a.square();
        break;
    case ActivationKind::relu:
        d = (a > S(0)).template cast<S>();
        a = a.max(S(0));
        break;
    case ActivationKind::identity: break;
    }
}

} // namespace

template <typename S>
BasicInferenceNetwork<S>::BasicInferenceNetwork(const Sequential& net, const Standardizer* input_standardizer,
                                                WeightFormat format)
{
    if (net.empty()) throw std::invalid_argument("InferenceNetwork: empty network");
    m_in = net.in_features();
    if (m_in == 0 && input_standardizer) m_in = input_standardizer->features();
    if (m_in == 0) throw std::invalid_argument("InferenceNetwork: cannot infer the input width");
    if (input_standardizer && !input_standardizer->empty() && input_standardizer->features() != m_in)
        throw std::invalid_argument("InferenceNetwork: standardizer width does not match the network input");

    Compiler c;
    int cur = c.new_buffer(m_in);
    if (input_standardizer && !input_standardizer->empty()) {
        const VectorXd s = input_standardizer->stddev().cwiseInverse();
        const VectorXd t = -input_standardizer->mean().cwiseProduct(s);
        cur = c.scale(cur, s, t);
    }
    cur = c.compile(net, cur);
    if (cur == 0) {  // identity network: still produce a separate output buffer
        cur = c.scale(cur, VectorXd::Ones(m_in), VectorXd::Zero(m_in));
    }
    c.fold_scales_forward(cur);
    m_output = cur;
    m_out = c.sizes[static_cast<std::size_t>(cur)];

    constexpr Index R = panel_rows<S>();
    for (auto& d : c.ops) {
        Op op;
        op.kind = d.kind;
        op.src = d.src;
        op.dst = d.dst;
        op.accumulate = d.accumulate;
        op.act = d.act;
        if (d.kind == Op::Kind::affine) {
            op.in = d.W.cols();
            op.out = d.W.rows();
            op.W = d.W.cast<S>();
            op.b = padded_vector<S>(d.b);
            pack_panels(op.packed, op.out, op.in, R, [&](Index i, Index j) { return op.W(i, j); });
            constexpr Index RT = transposed_panel_rows<S>();
            const Index t_panels = (op.in + RT - 1) / RT;
            op.packed_t.assign(static_cast<std::size_t>(t_panels * op.out * RT), S(0));
            for (Index p = 0; p < t_panels; ++p)
                for (Index i = 0; i < op.out; ++i)
                    for (Index r = 0; r < RT && p * RT + r < op.in; ++r)
                        op.packed_t[static_cast<std::size_t>((p * op.out + i) * RT + r)] = op.W(i, p * RT + r);
        } else {
            op.out = c.sizes[static_cast<std::size_t>(d.dst)];
            op.in = c.sizes[static_cast<std::size_t>(d.src)];
            if (d.kind == Op::Kind::scale) {
                op.b = d.b.cast<S>();
                op.t = d.t.cast<S>();
            }
        }
        m_ops.push_back(std::move(op));
    }
    m_buffer_size = c.sizes;
    for (Index n : m_buffer_size) m_buffers.push_back(Vector::Zero(padded<S>(n)));
    m_pre.resize(m_ops.size());
    for (std::size_t i = 0; i < m_ops.size(); ++i)
        if (m_ops[i].act != ActivationKind::identity) m_pre[i] = Vector::Zero(m_ops[i].out);
    m_adjoint.resize(m_buffers.size());
    set_weight_format(format);
}

template <typename S>
void BasicInferenceNetwork<S>::set_weight_format(WeightFormat format)
{
    if constexpr (!std::is_same_v<S, float>) {
        if (format != WeightFormat::f32)
            throw std::invalid_argument("InferenceNetworkD: weight format " + to_string(format) +
                                        " is for the float InferenceNetwork (the double network keeps f64 weights)");
    } else {
        constexpr Index R = panel_rows<float>();
        for (Op& op : m_ops) {
            op.packed_f16 = {};
            op.packed_int8 = {};
            op.row_scale = Vector();
            if (op.kind != Op::Kind::affine) continue;
            if (format == WeightFormat::f16) {
                pack_panels(op.packed_f16, op.out, op.in, R, [&](Index i, Index j) { return float_to_half(op.W(i, j)); });
            } else if (format == WeightFormat::int8) {
                const QuantizedRows rows = quantize_rows(op.W);
                pack_panels(op.packed_int8, op.out, op.in, R, [&](Index i, Index j) { return rows.q(i, j); });
                op.row_scale = Vector::Ones(padded<float>(op.out));
                op.row_scale.head(op.out) = rows.scale;
            }
        }
    }
    m_format = format;
}

template <typename S>
void BasicInferenceNetwork<S>::affine(const Op& op, bool full_precision)
{
    Vector& y = m_buffers[static_cast<std::size_t>(op.dst)];
    const S* x = m_buffers[static_cast<std::size_t>(op.src)].data();
    const Index panels = y.size() / panel_rows<S>();
    if constexpr (std::is_same_v<S, float>) {
        if (!full_precision && m_format == WeightFormat::f16) {
            packed_gemv_reduced(op.packed_f16.data(), nullptr, op.b.data(), x, op.in, panels, y.data(), op.accumulate);
            return;
        }
        if (!full_precision && m_format == WeightFormat::int8) {
            packed_gemv_reduced(op.packed_int8.data(), op.row_scale.data(), op.b.data(), x, op.in, panels, y.data(),
                                op.accumulate);
            return;
        }
    }
    packed_gemv<S>(op.packed.data(), op.b.data(), x, op.in, panels, y.data(), op.accumulate);
}

template <typename S>
void BasicInferenceNetwork<S>::run(bool record_tape, std::size_t end)
{
    for (std::size_t i = 0; i < end; ++i) {
        const Op& op = m_ops[i];
        auto src = m_buffers[static_cast<std::size_t>(op.src)].head(op.in);
        auto dst = m_buffers[static_cast<std::size_t>(op.dst)].head(op.out);
        switch (op.kind) {
        case Op::Kind::affine: affine(op, record_tape); break;
        case Op::Kind::scale: dst.array() = op.b.array() * src.array() + op.t.array(); break;
        case Op::Kind::act: dst = src; break;
        case Op::Kind::add: dst += src; break;
        }
        if (op.act != ActivationKind::identity) {
            if (record_tape) m_pre[i] = dst;
            auto a = dst.array();
            apply_activation(op.act, a);
        }
    }
}

template <typename S>
typename BasicInferenceNetwork<S>::ConstVectorMap BasicInferenceNetwork<S>::evaluate(const Eigen::Ref<const Vector>& x)
{
    assert(x.size() == m_in);
    m_buffers[0].head(m_in) = x;
    run(false, m_ops.size());
    return ConstVectorMap(m_buffers[static_cast<std::size_t>(m_output)].data(), m_out);
}

template <typename S>
void BasicInferenceNetwork<S>::evaluate(const S* x, S* y)
{
    m_buffers[0].head(m_in) = Eigen::Map<const Vector>(x, m_in);
    run(false, m_ops.size());
    Eigen::Map<Vector>(y, m_out) = m_buffers[static_cast<std::size_t>(m_output)].head(m_out);
}

template <typename S>
void BasicInferenceNetwork<S>::gemv_only()
{
    for (const Op& op : m_ops) {
        if (op.kind != Op::Kind::affine) continue;
        Vector& y = m_buffers[static_cast<std::size_t>(op.dst)];
        const S* x = m_buffers[static_cast<std::size_t>(op.src)].data();
        const Index panels = y.size() / panel_rows<S>();
        if constexpr (std::is_same_v<S, float>) {
            if (m_format == WeightFormat::f16) {
                packed_gemv_reduced(op.packed_f16.data(), nullptr, nullptr, x, op.in, panels, y.data(), false);
                continue;
            }
            if (m_format == WeightFormat::int8) {  // the row scales are part of the int8 product
                packed_gemv_reduced(op.packed_int8.data(), op.row_scale.data(), nullptr, x, op.in, panels, y.data(), false);
                continue;
            }
        }
        packed_gemv<S>(op.packed.data(), nullptr, x, op.in, panels, y.data(), false);
    }
}

template <typename S>
bool BasicInferenceNetwork<S>::output_is_plain_affine() const
{
    const Op& last = m_ops.back();
    if (last.kind != Op::Kind::affine || last.accumulate || last.act != ActivationKind::identity || last.dst != m_output)
        return false;
    for (std::size_t i = 0; i + 1 < m_ops.size(); ++i)
        if (m_ops[i].dst == m_output) return false;
    return true;
}

template <typename S>
void BasicInferenceNetwork<S>::jacobian_rows(const Eigen::Ref<const Vector>& x, const std::vector<Index>& rows,
                                             Eigen::Ref<Matrix> J, JacobianMode mode)
{
    const Index k = static_cast<Index>(rows.size());
    if (J.rows() != k || J.cols() != m_in)
        throw std::invalid_argument("InferenceNetwork::jacobian_rows: J must be rows.size() × in_features()");
    for (Index r : rows)
        if (r < 0 || r >= m_out) throw std::out_of_range("InferenceNetwork::jacobian_rows: row out of range");
    if (mode == JacobianMode::automatic) mode = k <= m_in ? JacobianMode::reverse : JacobianMode::forward;

    // If the output is produced by a single plain affine op (the PCA layer), skip its
    // primal and use W(rows, :) directly.
    const Op& last = m_ops.back();
    const bool special = output_is_plain_affine();
    const std::size_t end = special ? m_ops.size() - 1 : m_ops.size();

    // Primal pass with the tape (ops before `end` only).
    m_buffers[0].head(m_in) = x;
    run(true, end);
    if (special) {
        m_rows_weight.resize(k, last.in);
        for (Index i = 0; i < k; ++i) m_rows_weight.row(i) = last.W.row(rows[static_cast<std::size_t>(i)]);
    }

    if (mode == JacobianMode::reverse) {
        // Adjoints with rows padded to whole panels (the packed kernel writes full panels).
        for (std::size_t b = 0; b < m_adjoint.size(); ++b) {
            m_adjoint[b].resize(padded<S>(m_buffer_size[b]), k);
            m_adjoint[b].setZero();
        }
        if (special) {
            m_adjoint[static_cast<std::size_t>(last.src)].topRows(last.in) = m_rows_weight.transpose();
        } else {
            for (Index i = 0; i < k; ++i)
                m_adjoint[static_cast<std::size_t>(m_output)](rows[static_cast<std::size_t>(i)], i) = S(1);
        }
        for (std::size_t i = end; i-- > 0;) {
            const Op& op = m_ops[i];
            Matrix& a_dst = m_adjoint[static_cast<std::size_t>(op.dst)];
            Matrix& a_src = m_adjoint[static_cast<std::size_t>(op.src)];
            scale_rows_by_derivative(op.act, m_pre[i], a_dst.topRows(op.out));
            switch (op.kind) {
            case Op::Kind::affine: {
                constexpr Index RT = transposed_panel_rows<S>();
                const Index t_panels = (op.in + RT - 1) / RT;
                for (Index c = 0; c < k;) {
                    const Index kc = std::min<Index>(3, k - c);
                    const S* A = a_dst.data() + c * a_dst.rows();
                    S* Y = a_src.data() + c * a_src.rows();
                    if (kc == 3)
                        packed_transpose_product<S, 3>(op.packed_t.data(), op.out, t_panels, A, a_dst.rows(), Y, a_src.rows());
                    else if (kc == 2)
                        packed_transpose_product<S, 2>(op.packed_t.data(), op.out, t_panels, A, a_dst.rows(), Y, a_src.rows());
                    else
                        packed_transpose_product<S, 1>(op.packed_t.data(), op.out, t_panels, A, a_dst.rows(), Y, a_src.rows());
                    c += kc;
                }
                if (!op.accumulate) a_dst.setZero();
                break;
            }
            case Op::Kind::scale:
                a_src.topRows(op.in) += op.b.asDiagonal() * a_dst.topRows(op.out);
                a_dst.setZero();
                break;
            case Op::Kind::act:
                a_src.topRows(op.in) += a_dst.topRows(op.out);
                a_dst.setZero();
                break;
            case Op::Kind::add: a_src.topRows(op.in) += a_dst.topRows(op.out); break;
            }
        }
        J = m_adjoint[0].topRows(m_in).transpose();
        return;
    }

    // Forward mode: tangents of every buffer, in × in identity at the input.
    for (std::size_t b = 0; b < m_adjoint.size(); ++b) m_adjoint[b].resize(m_buffer_size[b], m_in);
    m_adjoint[0].setIdentity();
    for (std::size_t i = 0; i < end; ++i) {
        const Op& op = m_ops[i];
        Matrix& t_dst = m_adjoint[static_cast<std::size_t>(op.dst)];
        const Matrix& t_src = m_adjoint[static_cast<std::size_t>(op.src)];
        switch (op.kind) {
        case Op::Kind::affine:
            if (op.accumulate)
                t_dst.noalias() += op.W * t_src;
            else
                t_dst.noalias() = op.W * t_src;
            break;
        case Op::Kind::scale: t_dst = op.b.asDiagonal() * t_src; break;
        case Op::Kind::act: t_dst = t_src; break;
        case Op::Kind::add: t_dst += t_src; break;
        }
        scale_rows_by_derivative(op.act, m_pre[i], t_dst);
    }
    if (special) {
        J.noalias() = m_rows_weight * m_adjoint[static_cast<std::size_t>(last.src)];
    } else {
        const Matrix& t_out = m_adjoint[static_cast<std::size_t>(m_output)];
        for (Index i = 0; i < k; ++i) J.row(i) = t_out.row(rows[static_cast<std::size_t>(i)]);
    }
}

namespace {

/// Column blocks for the batched passes: the threads available outside a parallel region
/// (one block inside one, or for small batches); each block runs every op on its columns.
int column_blocks(Index columns)
{
    if (omp_in_parallel() || columns < 64) return 1;
    return int(std::min<Index>(omp_get_max_threads(), columns / 32));
}

/// First column of `block` of `blocks` over `columns`. Inner edges fall on multiples of 8, so
/// every block but the last is whole panels of Eigen's GEMM kernel (4 columns wide; its last
/// columns, short of a panel, take another kernel with another rounding): each column then
/// gets the round-off it gets in the one-block product, and a batch's numbers do not depend
/// on the thread count.
Index block_start(int block, int blocks, Index columns)
{
    if (block >= blocks) return columns;
    return columns * block / blocks / 8 * 8;
}

} // namespace

template <typename S>
Eigen::Map<const typename BasicInferenceNetwork<S>::Matrix>
BasicInferenceNetwork<S>::forward_batch(const Eigen::Ref<const Matrix>& X, bool record)
{
    if (X.rows() != m_in)
        throw std::invalid_argument("InferenceNetwork::forward_batch: expected " + std::to_string(m_in) +
                                    " input rows, got " + std::to_string(X.rows()));
    const Index B = X.cols();
    m_batch.resize(m_buffers.size());
    m_batch_derivative.resize(m_ops.size());
    m_batch[0].resize(m_in, B) = X;
    for (std::size_t b = 1; b < m_batch.size(); ++b) m_batch[b].resize(m_buffer_size[b], B);
    for (std::size_t i = 0; i < m_ops.size(); ++i) {
        if (record && m_ops[i].act != ActivationKind::identity) m_batch_derivative[i].resize(m_ops[i].out, B);
    }
    const int blocks = column_blocks(B);
    if (m_gemm.size() < std::size_t(blocks)) m_gemm.resize(std::size_t(blocks));
    if (m_activation_scratch.size() < std::size_t(blocks)) m_activation_scratch.resize(std::size_t(blocks));
    auto run_block = [&](Index b) {
        const int block = int(b);
        const Index c0 = block_start(block, blocks, B), n = block_start(block + 1, blocks, B) - c0;
        GemmWorkspace<S>& ws = m_gemm[std::size_t(block)];
        for (std::size_t i = 0; i < m_ops.size(); ++i) {
            const Op& op = m_ops[i];
            const auto src = m_batch[static_cast<std::size_t>(op.src)].view().middleCols(c0, n);
            auto dst = m_batch[static_cast<std::size_t>(op.dst)].view().middleCols(c0, n);
            switch (op.kind) {
            case Op::Kind::affine:
                gemm<S>(op.W, false, src, dst, op.accumulate ? GemmOp::add : GemmOp::assign, ws);
                dst.colwise() += op.b.head(op.out);
                break;
            case Op::Kind::scale: dst = (src.array().colwise() * op.b.array()).colwise() + op.t.array(); break;
            case Op::Kind::act: dst = src; break;
            case Op::Kind::add: dst += src; break;
            }
            if (op.act != ActivationKind::identity) {
                auto a = dst.array();
                if (record)
                    activate_with_derivative(op.act, a, m_batch_derivative[i].view().middleCols(c0, n).array(),
                                             m_activation_scratch[std::size_t(block)]);
                else
                    apply_activation(op.act, a);
            }
        }
    };
    parallel_for(blocks, blocks > 1, run_block);  // one block per thread (blocks ≤ threads)
    m_batch_columns = record ? B : -1;
    return std::as_const(m_batch[static_cast<std::size_t>(m_output)]).view();
}

template <typename S>
Eigen::Map<const typename BasicInferenceNetwork<S>::Matrix>
BasicInferenceNetwork<S>::vjp_batch(const Eigen::Ref<const Matrix>& dY)
{
    const Index B = dY.cols();
    if (m_batch_columns != B || dY.rows() != m_out)
        throw std::invalid_argument("InferenceNetwork::vjp_batch: dY must be out_features × the columns of the last "
                                    "recorded forward_batch");
    m_batch_adjoint.resize(m_buffers.size());
    for (std::size_t b = 0; b < m_batch_adjoint.size(); ++b) m_batch_adjoint[b].resize(m_buffer_size[b], B);
    // The output layer (the PCA layer) reads dY directly when it alone writes the output.
    std::size_t end = m_ops.size();
    const Op& last = m_ops.back();
    const bool direct = output_is_plain_affine();
    if (direct) --end;
    const int blocks = column_blocks(B);
    if (m_gemm.size() < std::size_t(blocks)) m_gemm.resize(std::size_t(blocks));
    auto run_block = [&](Index b) {
        const int block = int(b);
        const Index c0 = block_start(block, blocks, B), n = block_start(block + 1, blocks, B) - c0;
        GemmWorkspace<S>& ws = m_gemm[std::size_t(block)];
        auto adjoint = [&](int buffer) { return m_batch_adjoint[static_cast<std::size_t>(buffer)].view().middleCols(c0, n); };
        // Zeroed for accumulation, except the output's when the output layer reads dY.
        for (std::size_t b = 0; b < m_batch_adjoint.size(); ++b) {
            if (!(direct && int(b) == m_output)) adjoint(int(b)).setZero();
        }
        if (direct)
            gemm<S>(last.W, true, dY.middleCols(c0, n), adjoint(last.src), GemmOp::add, ws);
        else
            adjoint(m_output) = dY.middleCols(c0, n);
        for (std::size_t i = end; i-- > 0;) {
            const Op& op = m_ops[i];
            auto a_dst = adjoint(op.dst);
            auto a_src = adjoint(op.src);
            if (op.act != ActivationKind::identity)
                a_dst.array() *= m_batch_derivative[i].view().middleCols(c0, n).array();
            switch (op.kind) {
            case Op::Kind::affine:
                gemm<S>(op.W, true, a_dst, a_src, GemmOp::add, ws);
                if (!op.accumulate) a_dst.setZero();
                break;
            case Op::Kind::scale:
                a_src += op.b.head(op.in).asDiagonal() * a_dst;
                a_dst.setZero();
                break;
            case Op::Kind::act:
                a_src += a_dst;
                a_dst.setZero();
                break;
            case Op::Kind::add: a_src += a_dst; break;
            }
        }
    };
    parallel_for(blocks, blocks > 1, run_block);  // one block per thread (blocks ≤ threads)
    return std::as_const(m_batch_adjoint[0]).view();
}

template <typename S>
long long BasicInferenceNetwork<S>::multiply_adds() const
{
    long long n = 0;
    for (const Op& op : m_ops)
        if (op.kind == Op::Kind::affine) n += static_cast<long long>(op.in) * op.out;
    return n;
}

template <typename S>
long long BasicInferenceNetwork<S>::weight_bytes() const
{
    long long n = 0;
    for (const Op& op : m_ops) {
        switch (m_format) {
        case WeightFormat::f32: n += static_cast<long long>(op.packed.size() * sizeof(S)); break;
        case WeightFormat::f16: n += static_cast<long long>(op.packed_f16.size() * sizeof(std::uint16_t)); break;
        case WeightFormat::int8:
            n += static_cast<long long>(op.packed_int8.size()) + static_cast<long long>(op.row_scale.size()) * sizeof(S);
            break;
        }
    }
    return n;
}

template <typename S>
std::string BasicInferenceNetwork<S>::describe() const
{
    std::ostringstream os;
    os << "weights " << (std::is_same_v<S, float> ? to_string(m_format) : std::string("f64")) << "\n";
    for (const Op& op : m_ops) {
        switch (op.kind) {
        case Op::Kind::affine: os << (op.accumulate ? "affine+= " : "affine ") << op.in << "->" << op.out; break;
        case Op::Kind::scale: os << "scale " << op.out; break;
        case Op::Kind::act: os << "act " << op.out; break;
        case Op::Kind::add: os << "add " << op.out; break;
        }
        if (op.act != ActivationKind::identity) os << " " << to_string(op.act);
        os << " [" << op.src << " -> " << op.dst << "]\n";
    }
    return os.str();
}

template class BasicInferenceNetwork<float>;
template class BasicInferenceNetwork<double>;

} // namespace lb::nn
