// Weight formats of the float inference network (nn/weight_format.hpp): names, the
// int8 per-row quantisation and the dequantised weights.
#include <gtest/gtest.h>

#include <stdexcept>

#include "core/rng.hpp"
#include "nn/half.hpp"
#include "nn/weight_format.hpp"

namespace lb::nn {
namespace {

TEST(WeightFormat, NamesRoundTripAndABadNameIsExplained)
{
    for (WeightFormat f : {WeightFormat::f32, WeightFormat::f16, WeightFormat::int8})
        EXPECT_EQ(weight_format_from_string(to_string(f)), f);
    EXPECT_EQ(to_string(WeightFormat::f16), "f16");
    EXPECT_EQ(bytes_per_weight(WeightFormat::int8), 1);
    try {
        weight_format_from_string("bf16");
        FAIL() << "bf16 accepted";
    } catch (const std::invalid_argument& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("'bf16'"), std::string::npos) << what;
        for (const char* name : {"f32", "f16", "int8"}) EXPECT_NE(what.find(name), std::string::npos) << what;
    }
    EXPECT_THROW(weight_format_from_string("F16"), std::invalid_argument);
    EXPECT_THROW(weight_format_from_string(""), std::invalid_argument);
}

TEST(WeightFormat, Int8RowsUseTheirLargestEntry)
{
    Rng rng(5);
    Eigen::MatrixXf W(4, 9);
    for (Index i = 0; i < W.rows(); ++i)
        for (Index j = 0; j < W.cols(); ++j) W(i, j) = float(rng.uniform(-1.0, 1.0) * std::pow(10.0, double(i) - 2));
    W.row(2).setZero();
    W(3, 4) = -12.5f;  // the largest magnitude (the row is within ±10), negative
    const QuantizedRows r = quantize_rows(W);
    ASSERT_EQ(r.q.rows(), 4);
    ASSERT_EQ(r.q.cols(), 9);
    EXPECT_EQ(r.scale[2], 1.0f);
    EXPECT_TRUE((r.q.row(2).array() == 0).all());
    EXPECT_EQ(r.q(3, 4), -127);
    EXPECT_EQ(r.scale[3], 12.5f / 127.0f);
    for (Index i = 0; i < W.rows(); ++i) {
        if (i == 2) continue;
        EXPECT_EQ(r.q.row(i).cast<int>().cwiseAbs().maxCoeff(), 127) << "row " << i;
        for (Index j = 0; j < W.cols(); ++j) {
            const double error = std::abs(double(W(i, j)) - double(r.scale[i]) * r.q(i, j));
            EXPECT_LE(error, 0.5 * r.scale[i] * (1 + 1e-6)) << i << ", " << j;
        }
    }
    const Eigen::MatrixXd D = dequantized(W, WeightFormat::int8);
    EXPECT_EQ(D(3, 4), -127.0 * double(12.5f / 127.0f));
    EXPECT_EQ(D(1, 2), double(r.scale[1]) * r.q(1, 2));
    EXPECT_TRUE((dequantized(W, WeightFormat::f32).array() == W.cast<double>().array()).all());
    EXPECT_EQ(dequantized(W, WeightFormat::f16)(0, 0), double(round_to_half(W(0, 0))));
}

} // namespace
} // namespace lb::nn
