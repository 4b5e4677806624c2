#pragma once
// How the float InferenceNetwork stores the weights that evaluate() streams
// (nn/inference_network.hpp). Accumulation, biases, BatchNorm scales and activations
// stay float32 in every format; only the bytes per weight change.
//   f32   4 bytes, the folded weights rounded to float (the default)
//   f16   2 bytes, each float weight rounded to the nearest IEEE half (ties to even,
//         nn/half.hpp); |Ŵ − W| ≤ 2⁻¹¹ |W| in the normal range, 2⁻²⁵ absolute below 2⁻¹⁴
//   int8  1 byte, symmetric per output row: s_i = max_j |W(i, j)| / 127,
//         q(i, j) = round(W(i, j) / s_i) ∈ [−127, 127], Ŵ(i, j) = s_i q(i, j), so
//         |Ŵ − W| ≤ s_i / 2 (a row of zeros gets s_i = 1 and q = 0)
#include <cstdint>
#include <string>

#include <Eigen/Core>

namespace lb::nn {

enum class WeightFormat { f32, f16, int8 };

/// "f32", "f16" or "int8".
std::string to_string(WeightFormat format);
/// Inverse of to_string; throws std::invalid_argument naming the value and the valid ones.
WeightFormat weight_format_from_string(const std::string& name);
/// Bytes per stored weight: 4, 2 or 1.
int bytes_per_weight(WeightFormat format);

/// int8 rows: W(i, :) ≈ scale[i] · q(i, :).
struct QuantizedRows {
    Eigen::Matrix<std::int8_t, Eigen::Dynamic, Eigen::Dynamic> q;  ///< rows × cols
    Eigen::VectorXf scale;                                         ///< rows, > 0
};

/// Symmetric per-row int8 quantisation of W (rows × cols), as in the header comment.
QuantizedRows quantize_rows(const Eigen::Ref<const Eigen::MatrixXf>& W);

/// The weights a format stores, as doubles (exact): W itself (f32), W rounded to half
/// (f16), or scale[i] · q(i, j) (int8). rows × cols, as W.
Eigen::MatrixXd dequantized(const Eigen::Ref<const Eigen::MatrixXf>& W, WeightFormat format);

} // namespace lb::nn
