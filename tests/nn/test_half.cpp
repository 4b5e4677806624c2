// The software float ↔ half conversions (nn/half.hpp): exact round trips, rounding to
// nearest with ties to even, overflow, subnormals, against the F16C instructions where
// they are compiled in.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__F16C__)
#include <immintrin.h>
#endif

#include "core/rng.hpp"
#include "nn/half.hpp"

namespace lb::nn {
namespace {

bool is_nan_half(std::uint16_t h) { return (h & 0x7c00u) == 0x7c00u && (h & 0x3ffu) != 0; }

TEST(Half, KnownValues)
{
    EXPECT_EQ(float_to_half(0.0f), 0x0000);
    EXPECT_EQ(float_to_half(-0.0f), 0x8000);
    EXPECT_EQ(float_to_half(1.0f), 0x3c00);
    EXPECT_EQ(float_to_half(-2.0f), 0xc000);
    EXPECT_EQ(float_to_half(65504.0f), 0x7bff);                 // largest finite half
    EXPECT_EQ(float_to_half(std::ldexp(1.0f, -14)), 0x0400);    // smallest normal
    EXPECT_EQ(float_to_half(std::ldexp(1.0f, -24)), 0x0001);    // smallest subnormal
    EXPECT_EQ(float_to_half(std::ldexp(1023.0f, -24)), 0x03ff); // largest subnormal
    // 1/3 = 0x3eaaaaab in float; in half 0x3555 = 0.333251953125 (the next, 0x3556, is farther).
    EXPECT_EQ(float_to_half(1.0f / 3.0f), 0x3555);
    EXPECT_EQ(half_to_float(0x3555), 0.333251953125f);
    EXPECT_EQ(half_to_float(0x7bff), 65504.0f);
    EXPECT_EQ(half_to_float(0x0001), std::ldexp(1.0f, -24));
    EXPECT_EQ(half_to_float(0x8001), -std::ldexp(1.0f, -24));
    EXPECT_TRUE(std::signbit(half_to_float(0x8000)));
    EXPECT_EQ(half_to_float(0x7c00), std::numeric_limits<float>::infinity());
    EXPECT_EQ(half_to_float(0xfc00), -std::numeric_limits<float>::infinity());
    // Overflow: 65519.99 rounds down to 65504; 65520 is a tie and goes to the even neighbour, inf.
    EXPECT_EQ(float_to_half(std::nextafter(65520.0f, 0.0f)), 0x7bff);
    EXPECT_EQ(float_to_half(65520.0f), 0x7c00);
    EXPECT_EQ(float_to_half(-1e10f), 0xfc00);
    EXPECT_EQ(float_to_half(std::numeric_limits<float>::infinity()), 0x7c00);
    EXPECT_TRUE(is_nan_half(float_to_half(std::numeric_limits<float>::quiet_NaN())));
    EXPECT_TRUE(std::isnan(half_to_float(0x7e00)));
    // Underflow: 2⁻²⁵ is a tie between 0 and 2⁻²⁴ (to even: 0); just above it rounds up.
    EXPECT_EQ(float_to_half(std::ldexp(1.0f, -25)), 0x0000);
    EXPECT_EQ(float_to_half(std::nextafter(std::ldexp(1.0f, -25), 1.0f)), 0x0001);
    EXPECT_EQ(float_to_half(-std::ldexp(1.0f, -30)), 0x8000);
    EXPECT_EQ(float_to_half(std::numeric_limits<float>::denorm_min()), 0x0000);
}

TEST(Half, EveryFiniteHalfRoundTripsExactly)
{
    int finite = 0;
    for (std::uint32_t h = 0; h <= 0xffffu; ++h) {
        const auto bits = static_cast<std::uint16_t>(h);
        if ((bits & 0x7c00u) == 0x7c00u) continue;  // inf and NaN
        const float f = half_to_float(bits);
        ASSERT_TRUE(std::isfinite(f)) << std::hex << h;
        ASSERT_EQ(float_to_half(f), bits) << std::hex << "half 0x" << h << " -> " << f;
        ++finite;
    }
    EXPECT_EQ(finite, 63488);  // 2 · 31 · 1024
}

/// Between two consecutive positive halves a < b, the midpoint goes to the one whose last
/// bit is 0, and anything strictly nearer to a side goes there (subnormals included).
TEST(Half, RoundsToNearestWithTiesToEven)
{
    int ties = 0;
    for (std::uint16_t h = 0; h < 0x7bff; ++h) {
        const float a = half_to_float(h), b = half_to_float(static_cast<std::uint16_t>(h + 1));
        const float mid = float((double(a) + double(b)) / 2);  // exact: halves have 11 bits
        ASSERT_EQ(double(mid), (double(a) + double(b)) / 2);
        const std::uint16_t even = (h & 1u) ? static_cast<std::uint16_t>(h + 1) : h;
        ASSERT_EQ(float_to_half(mid), even) << std::hex << "tie above half 0x" << h;
        ASSERT_EQ(float_to_half(-mid), static_cast<std::uint16_t>(even | 0x8000u)) << std::hex << "tie below half 0x" << (h | 0x8000);
        ASSERT_EQ(float_to_half(std::nextafter(mid, 0.0f)), h) << std::hex << "just below the tie above 0x" << h;
        ASSERT_EQ(float_to_half(std::nextafter(mid, 1e9f)), static_cast<std::uint16_t>(h + 1)) << std::hex << "just above the tie above 0x" << h;
        ++ties;
    }
    EXPECT_EQ(ties, 0x7bff);
}

#if defined(__F16C__)
std::uint16_t f16c_to_half(float x)
{
    return static_cast<std::uint16_t>(_mm_extract_epi16(_mm_cvtps_ph(_mm_set_ss(x), _MM_FROUND_TO_NEAREST_INT), 0));
}
float f16c_to_float(std::uint16_t h) { return _mm_cvtss_f32(_mm_cvtph_ps(_mm_cvtsi32_si128(h))); }
#endif

TEST(Half, AgreesWithF16C)
{
#if defined(__F16C__)
    for (std::uint32_t h = 0; h <= 0xffffu; ++h) {
        const auto bits = static_cast<std::uint16_t>(h);
        const float hw = f16c_to_float(bits), sw = half_to_float(bits);
        if (std::isnan(hw)) {
            ASSERT_TRUE(std::isnan(sw)) << std::hex << h;
            continue;
        }
        ASSERT_EQ(bits_of(sw), bits_of(hw)) << std::hex << "half 0x" << h;
    }
    // Every float whose exponent is in or near the half range, on a stride through its
    // fraction bits, plus random bit patterns over the whole float range.
    long compared = 0;
    for (std::uint32_t u = 0x32000000u; u < 0x48000000u; u += 97) {
        for (std::uint32_t s : {0u, 0x80000000u}) {
            const float x = float_of(u | s);
            ASSERT_EQ(float_to_half(x), f16c_to_half(x)) << std::hex << "float bits 0x" << (u | s);
            ++compared;
        }
    }
    Rng rng(17);
    for (int i = 0; i < 1000000; ++i) {
        const auto u = static_cast<std::uint32_t>(rng.index(Index(1) << 32));
        const float x = float_of(u);
        const std::uint16_t sw = float_to_half(x), hw = f16c_to_half(x);
        if (std::isnan(x)) {
            ASSERT_TRUE(is_nan_half(sw) && is_nan_half(hw)) << std::hex << u;
            continue;
        }
        ASSERT_EQ(sw, hw) << std::hex << "float bits 0x" << u;
        ++compared;
    }
    EXPECT_GT(compared, 3000000);
#else
    GTEST_SKIP() << "built without F16C";
#endif
}

} // namespace
} // namespace lb::nn
