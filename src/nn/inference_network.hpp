#pragma once
// Fast single-sample inference (batch 1, one thread), float by default.
//
// A trained Sequential (eval mode) is compiled into a short list of fused ops on
// preallocated buffers:
//   affine:  dst (=|+=) W src + b, then the activation, in one op
//   scale:   dst = s ⊙ src + t          (only a BatchNorm that cannot be folded)
//   act:     dst = act(src)             (only an activation that cannot be fused)
//   add:     dst += src                 (identity skip of a residual block)
// Folding rules (done in double precision before rounding to Scalar):
//   * BatchNorm after Linear(s): s ⊙ (W x + b) + t = (diag(s) W) x + (s ⊙ b + t), applied
//     to every Linear accumulating into that buffer (the residual projection too);
//   * a scale whose output is read only by Linears (the input Standardizer, a leading
//     BatchNorm) is folded forward: W (s ⊙ x + t) + b = (W diag(s)) x + (W t + b);
//   * an activation is fused into the Linear that produced its input.
// The armadillo decoder (12 → res 200 ×3 → 50 → 10,020) becomes 9 GEMVs + 2 adds.
//
// Weights are packed in row panels of R = 8 SIMD vectors (64 floats / 32 doubles):
// panel p holds rows [pR, pR+R) as in consecutive R-vectors (column j of the panel
// contiguous), so each GEMV streams its weights exactly once, sequentially, with R
// independent FMA accumulators held in registers (AVX2+FMA; a portable loop
// otherwise). Buffers are padded to whole panels. evaluate() performs no heap
// allocation (tested by counting malloc calls). The per-frame cost is bound by
// streaming the weights from L3 (≈3.9 MB float for the armadillo integrator +
// decoder); bench_nn's "gemv_bound" rows measure the GEMVs alone for comparison.
//
// Weight format (float network only; nn/weight_format.hpp): evaluate() and gemv_only()
// stream the weights as f32 (default), f16 or int8 in the same panel layout, converted to
// float in registers (F16C vcvtph2ps; AVX2 vpmovsxbd + vcvtdq2ps; scalar conversions in
// the portable loop) and accumulated in float32:
//   f16:   y = Ŵ x + b, Ŵ = W rounded to half;
//   int8:  y_i = s_i (q(i, :) · x) + b_i, the row scale applied once per row, before the bias.
// Biases, BatchNorm scales (folded ones are in W) and activations stay float32. The
// derivative paths (jacobian_rows, including its primal pass, forward_batch and
// vjp_batch) always use the float32 weights, so their results do not depend on the format.
// f32 gives the same bits as before the formats existed.
//
// jacobian_rows: a primal pass (skipping the final PCA layer when it is a plain
// Linear, whose Jacobian rows are just W(rows, :)) keeps the pre-activations, then
// reverse mode runs all requested rows at once through Wᵀ packed the same way
// (panels of 4 SIMD vectors, every weight vector loaded once for up to 3 rows), so
// one vertex costs about two passes over the hidden-layer weights. Forward mode
// (tangents = identity on the latent) uses Eigen products on plain copies of W.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "nn/activation.hpp"
#include "nn/network_derivatives.hpp"
#include "nn/sequential.hpp"
#include "nn/standardizer.hpp"
#include "nn/weight_format.hpp"
#include "nn/workspace.hpp"

namespace lb::nn {

enum class InferenceOpKind { affine, scale, act, add };

template <typename Scalar>
class BasicInferenceNetwork {
public:
    using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
    using Matrix = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;
    using ConstVectorMap = Eigen::Map<const Vector>;

    BasicInferenceNetwork() = default;
    /// Compile `net` as evaluated in eval mode (BatchNorm running statistics), with an
    /// optional input standardizer applied first, streaming its weights in `format` (see
    /// set_weight_format). Throws std::invalid_argument for an empty network or
    /// unsupported layer types.
    explicit BasicInferenceNetwork(const Sequential& net, const Standardizer* input_standardizer = nullptr,
                                   WeightFormat format = WeightFormat::f32);

    /// Re-pack the weights evaluate() and gemv_only() stream (allocates; not per frame).
    /// Throws std::invalid_argument for f16 or int8 on the double network.
    void set_weight_format(WeightFormat format);
    WeightFormat weight_format() const { return m_format; }

    Index in_features() const { return m_in; }
    Index out_features() const { return m_out; }

    /// y = net(x) for one sample. The returned view points into an internal buffer and
    /// is valid until the next call. No heap allocation.
    ConstVectorMap evaluate(const Eigen::Ref<const Vector>& x);
    /// Same, copying into y (size out_features()).
    void evaluate(const Scalar* x, Scalar* y);

    /// Rows `rows` of the Jacobian at x into J (rows.size() × in_features()); mode
    /// as for nn::jacobian_rows (automatic: reverse if rows.size() ≤ in). Workspaces
    /// are sized on the first call and reused (no allocation while the row count stays
    /// the same).
    void jacobian_rows(const Eigen::Ref<const Vector>& x, const std::vector<Index>& rows, Eigen::Ref<Matrix> J,
                       JacobianMode mode = JacobianMode::automatic);

    /// Batched evaluation (columns are samples) with the same fused ops, one GEMM per
    /// affine op: for the frozen decoder of a training loss, where every batch is decoded
    /// and then differentiated. With `record`, the pre-activations are kept for
    /// vjp_batch(). Returns out × B, a view of an internal buffer valid until the next
    /// batched call. The buffers and the GEMMs' packing space only grow: once they have
    /// seen the largest batch, nothing is allocated.
    Eigen::Map<const Matrix> forward_batch(const Eigen::Ref<const Matrix>& X, bool record = false);
    /// Jᵀ dY for every column at the points of the last forward_batch(record = true): one
    /// reverse pass, one GEMM per affine op. dY out × B; returns in × B, a view valid until
    /// the next batched call. No allocation once grown, as forward_batch.
    Eigen::Map<const Matrix> vjp_batch(const Eigen::Ref<const Matrix>& dY);

    /// Multiply-adds of one evaluate() (weights touched once each).
    long long multiply_adds() const;
    /// Bytes of packed weights streamed by one evaluate() in the current format (int8:
    /// the row scales included; biases are not counted in any format).
    long long weight_bytes() const;
    /// The weight format ("weights f16"; "weights f64" for the double network), then one
    /// line per op, e.g. "affine 12->200 swish [1 -> 2]".
    std::string describe() const;

    /// The packed GEMVs alone (no bias, no activation, no adds), into each op's
    /// output buffer: the memory/compute lower bound benchmarked beside evaluate().
    void gemv_only();

    struct Op {
        using Kind = InferenceOpKind;
        Kind kind = Kind::affine;
        int src = -1, dst = -1;
        bool accumulate = false;  ///< affine: dst += ... instead of dst = ...
        ActivationKind act = ActivationKind::identity;
        Index in = 0, out = 0;
        std::vector<Scalar, Eigen::aligned_allocator<Scalar>> packed;    ///< affine: panel-packed W
        std::vector<Scalar, Eigen::aligned_allocator<Scalar>> packed_t;  ///< affine: panel-packed Wᵀ (reverse mode)
        /// affine, f16 format: W rounded to half, panel-packed as `packed` (else empty)
        std::vector<std::uint16_t, Eigen::aligned_allocator<std::uint16_t>> packed_f16;
        /// affine, int8 format: q, panel-packed as `packed` (else empty)
        std::vector<std::int8_t, Eigen::aligned_allocator<std::int8_t>> packed_int8;
        Vector row_scale;  ///< affine, int8 format: s per row, padded to whole panels (else empty)
        Matrix W;   ///< affine: out × in, plain (derivatives)
        Vector b;   ///< affine: bias padded to whole panels;  scale: s
        Vector t;   ///< scale: shift
    };
    const std::vector<Op>& ops() const { return m_ops; }

private:
    /// Ops [0, end); with the tape, pre-activations are kept for the derivatives.
    void run(bool record_tape, std::size_t end);
    /// With `full_precision`, the float32 panels whatever the format (derivatives' primal).
    void affine(const Op& op, bool full_precision);
    /// True if the output is written by the last op alone, a plain affine one (the PCA
    /// layer): the derivatives then use its weights directly.
    bool output_is_plain_affine() const;

    Index m_in = 0, m_out = 0;
    WeightFormat m_format = WeightFormat::f32;
    std::vector<Op> m_ops;
    std::vector<Vector> m_buffers;     ///< padded to whole panels
    std::vector<Index> m_buffer_size;  ///< logical sizes
    int m_output = -1;

    // derivative workspaces
    std::vector<Vector> m_pre;                 ///< per op: pre-activation (tape)
    std::vector<Matrix> m_adjoint;             ///< per buffer: padded size × k (reverse) or size × in (forward)
    Matrix m_rows_weight;

    // batched workspaces: per buffer (logical size × B), and per op with an activation its
    // derivative at the recorded forward's pre-activations (the tape); per column block the
    // GEMMs' packing buffers
    std::vector<GrowingMatrix<Scalar>> m_batch, m_batch_derivative, m_batch_adjoint;
    std::vector<GemmWorkspace<Scalar>> m_gemm;
    std::vector<GrowingMatrix<Scalar>> m_activation_scratch;  ///< per column block
    Index m_batch_columns = -1;  ///< columns of the last recorded forward_batch (−1: none)
};

using InferenceNetwork = BasicInferenceNetwork<float>;
using InferenceNetworkD = BasicInferenceNetwork<double>;

extern template class BasicInferenceNetwork<float>;
extern template class BasicInferenceNetwork<double>;

} // namespace lb::nn
