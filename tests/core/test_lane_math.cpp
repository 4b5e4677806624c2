// lane_atan2 (core/lane_math.hpp) against std::atan2: random arguments over 20 orders of
// magnitude, arguments near the octant and reduction boundaries, signed zeros and
// infinities, and the same numbers from a SIMD loop as from a scalar call.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/lane_math.hpp"
#include "core/rng.hpp"

namespace lb {
namespace {

/// Distance of a from b in units of b's last place (b's ulp), or ∞ for a NaN mismatch.
double ulps(double a, double b)
{
    if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b) ? 0.0 : HUGE_VAL;
    const double ulp = std::nextafter(std::abs(b), HUGE_VAL) - std::abs(b);
    return std::abs(a - b) / ulp;
}

::testing::AssertionResult close_to_libm(double y, double x)
{
    const double a = lane_atan2(y, x), b = std::atan2(y, x);
    if (ulps(a, b) <= 4.0 || std::abs(a - b) <= 4e-16) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "lane_atan2(" << y << ", " << x << ") = " << a << ", std::atan2 " << b
                                         << " (" << ulps(a, b) << " ulp)";
}

TEST(LaneAtan2, RandomArgumentsWithinFourUlp)
{
    Rng rng(3);
    double worst = 0.0;
    for (int i = 0; i < 400000; ++i) {
        const double y = rng.uniform(-1.0, 1.0) * std::pow(10.0, rng.uniform(-10.0, 10.0));
        const double x = rng.uniform(-1.0, 1.0) * std::pow(10.0, rng.uniform(-10.0, 10.0));
        ASSERT_TRUE(close_to_libm(y, x));
        worst = std::max(worst, ulps(lane_atan2(y, x), std::atan2(y, x)));
    }
    EXPECT_GT(worst, 0.0);  // the comparison is not vacuous: it is a different algorithm
}

TEST(LaneAtan2, ReductionBoundariesAndAxes)
{
    const double tan_pi8 = std::sqrt(2.0) - 1.0;
    for (double t : {0.0, 1e-300, 1e-8, tan_pi8 * (1 - 1e-15), tan_pi8, tan_pi8 * (1 + 1e-15), 0.5,
                     1.0 - 1e-15, 1.0, 1.0 + 1e-15, 2.0, 1e8}) {
        for (double sy : {1.0, -1.0}) {
            for (double sx : {1.0, -1.0}) {
                EXPECT_TRUE(close_to_libm(sy * t, sx * 1.0));
                EXPECT_TRUE(close_to_libm(sy * 1.0, sx * t));
            }
        }
    }
    const double inf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(lane_atan2(0.0, -1.0), M_PI);
    EXPECT_EQ(lane_atan2(-0.0, -1.0), -M_PI);
    EXPECT_EQ(lane_atan2(0.0, 1.0), 0.0);
    EXPECT_TRUE(close_to_libm(1.0, 0.0));
    EXPECT_TRUE(close_to_libm(-1.0, -0.0));
    EXPECT_TRUE(close_to_libm(1.0, inf));
    EXPECT_TRUE(close_to_libm(inf, 1.0));
    EXPECT_EQ(lane_atan2(0.0, 0.0), 0.0);  // documented: std::atan2 gives ±0 or ±π here
    EXPECT_TRUE(std::isnan(lane_atan2(std::nan(""), 1.0)));
    EXPECT_TRUE(std::isnan(lane_atan2(1.0, std::nan(""))));
}

TEST(LaneAtan2, SimdLoopEqualsScalarCall)
{
    Rng rng(5);
    const int n = 1003;
    std::vector<double> y(n), x(n), out(n);
    for (int i = 0; i < n; ++i) {
        y[size_t(i)] = rng.uniform(-3.0, 3.0);
        x[size_t(i)] = rng.uniform(-3.0, 3.0);
    }
#pragma omp simd
    for (int i = 0; i < n; ++i) out[size_t(i)] = lane_atan2(y[size_t(i)], x[size_t(i)]);
    for (int i = 0; i < n; ++i) {
        EXPECT_TRUE(close_to_libm(y[size_t(i)], x[size_t(i)]));
        // FMA contraction may differ between the two code paths by round-off only.
        EXPECT_NEAR(out[size_t(i)], lane_atan2(y[size_t(i)], x[size_t(i)]), 1e-15);
    }
}

} // namespace
} // namespace lb
