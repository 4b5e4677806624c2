#include "nn/half.hpp"

#include <cmath>

namespace lb::nn {

namespace {

constexpr std::uint32_t float_exponent_mask = 0x7f800000u;
/// Float bits of 65520 = 65504 + half an ulp: from here on (the tie goes to the even
/// neighbour, 2¹⁶, which is out of range) a float rounds to inf.
constexpr std::uint32_t half_overflow = 0x477ff000u;
/// Float bits of 2⁻¹⁴, the smallest normal half.
constexpr std::uint32_t half_min_normal = 0x38800000u;
/// (127 − 15) << 23: re-biases a float exponent to a half one.
constexpr std::uint32_t exponent_rebias = 112u << 23;

} // namespace

std::uint16_t float_to_half(float x)
{
    const std::uint32_t u = bits_of(x);
    const auto sign = static_cast<std::uint16_t>((u >> 16) & 0x8000u);
    const std::uint32_t a = u & 0x7fffffffu;
    if (a >= float_exponent_mask) {  // inf or NaN (a NaN keeps its top fraction bits, quietened)
        const std::uint32_t nan = a > float_exponent_mask ? 0x200u | ((a >> 13) & 0x3ffu) : 0u;
        return static_cast<std::uint16_t>(sign | 0x7c00u | nan);
    }
    if (a >= half_overflow) return static_cast<std::uint16_t>(sign | 0x7c00u);
    if (a >= half_min_normal) {
        // Drop 13 fraction bits rounding to nearest even: add just under half an ulp, plus
        // one if the kept part is odd. A carry into the exponent is the correct result.
        const std::uint32_t rounded = a + 0xfffu + ((a >> 13) & 1u);
        return static_cast<std::uint16_t>(sign | ((rounded - exponent_rebias) >> 13));
    }
    // Subnormal half (or zero): the count of 2⁻²⁴ units, m · 2^(e − 150) / 2⁻²⁴ = m >> (126 − e)
    // for the float's significand m (implicit bit included) and biased exponent e.
    const int e = static_cast<int>(a >> 23);
    if (e < 102) return sign;  // below 2⁻²⁵: rounds to zero (2⁻²⁵ itself is a tie, to even 0)
    const std::uint32_t m = (a & 0x7fffffu) | 0x800000u;
    const int shift = 126 - e;  // 14 .. 24
    std::uint32_t q = m >> shift;
    const std::uint32_t rest = m & ((1u << shift) - 1u), half_unit = 1u << (shift - 1);
    if (rest > half_unit || (rest == half_unit && (q & 1u))) ++q;  // may reach 0x400, the smallest normal
    return static_cast<std::uint16_t>(sign | q);
}

float half_to_float(std::uint16_t h)
{
    const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
    const std::uint32_t e = (h >> 10) & 0x1fu, f = h & 0x3ffu;
    if (e == 0) {  // zero or subnormal: f · 2⁻²⁴, exact in float
        const float v = std::ldexp(static_cast<float>(f), -24);
        return sign ? -v : v;
    }
    if (e == 31) return float_of(sign | float_exponent_mask | (f << 13));
    return float_of(sign | ((e << 23) + exponent_rebias) | (f << 13));
}

} // namespace lb::nn
