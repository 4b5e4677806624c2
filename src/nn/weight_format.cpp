#include "nn/weight_format.hpp"

#include <cmath>
#include <stdexcept>

#include "nn/half.hpp"

namespace lb::nn {

namespace {
constexpr float int8_levels = 127.0f;  ///< symmetric range [−127, 127] (−128 unused)
}

std::string to_string(WeightFormat format)
{
    switch (format) {
    case WeightFormat::f32: return "f32";
    case WeightFormat::f16: return "f16";
    case WeightFormat::int8: return "int8";
    }
    return "?";
}

WeightFormat weight_format_from_string(const std::string& name)
{
    for (WeightFormat f : {WeightFormat::f32, WeightFormat::f16, WeightFormat::int8})
        if (name == to_string(f)) return f;
    throw std::invalid_argument("unknown weight format '" + name + "' (expected f32, f16 or int8)");
}

int bytes_per_weight(WeightFormat format)
{
    switch (format) {
    case WeightFormat::f32: return 4;
    case WeightFormat::f16: return 2;
    case WeightFormat::int8: return 1;
    }
    return 4;
}

QuantizedRows quantize_rows(const Eigen::Ref<const Eigen::MatrixXf>& W)
{
    QuantizedRows out;
    out.q.resize(W.rows(), W.cols());
    out.scale.resize(W.rows());
    for (Eigen::Index i = 0; i < W.rows(); ++i) {
        const float largest = W.cols() > 0 ? W.row(i).cwiseAbs().maxCoeff() : 0.0f;
        // A zero row (or one too small for a normal scale) stores zeros with scale 1.
        const float s = largest > 0.0f && std::isnormal(largest / int8_levels) ? largest / int8_levels : 1.0f;
        out.scale[i] = s;
        for (Eigen::Index j = 0; j < W.cols(); ++j) {
            // Divided in double so that the largest entry maps to exactly ±127.
            const double r = std::nearbyint(double(W(i, j)) / double(s));
            out.q(i, j) = static_cast<std::int8_t>(std::fmax(-127.0, std::fmin(127.0, r)));
        }
    }
    return out;
}

Eigen::MatrixXd dequantized(const Eigen::Ref<const Eigen::MatrixXf>& W, WeightFormat format)
{
    switch (format) {
    case WeightFormat::f32: return W.cast<double>();
    case WeightFormat::f16: return W.unaryExpr([](float w) { return double(round_to_half(w)); });
    case WeightFormat::int8: {
        const QuantizedRows r = quantize_rows(W);
        return r.scale.cast<double>().asDiagonal() * r.q.cast<double>();
    }
    }
    return W.cast<double>();
}

} // namespace lb::nn
