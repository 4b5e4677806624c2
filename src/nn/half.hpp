#pragma once
// IEEE 754 binary16 ("half") conversions in software, for the f16 weight format
// (nn/weight_format.hpp) and as the reference the F16C instructions are tested against.
//
// binary16: 1 sign bit, 5 exponent bits (bias 15), 10 fraction bits; largest finite 65504,
// smallest normal 2⁻¹⁴, smallest subnormal 2⁻²⁴. float → half rounds to nearest, ties to
// even (as F16C's vcvtps2ph with _MM_FROUND_TO_NEAREST_INT); a value that rounds to 65520
// or beyond becomes ±inf; NaN stays NaN (quiet, the top fraction bits kept). half → float
// is exact.
#include <cstdint>
#include <cstring>

namespace lb::nn {

/// The IEEE 754 bits of a float, and the float with those bits (std::bit_cast before C++20).
inline std::uint32_t bits_of(float x)
{
    std::uint32_t u;
    std::memcpy(&u, &x, sizeof u);
    return u;
}
inline float float_of(std::uint32_t u)
{
    float x;
    std::memcpy(&x, &u, sizeof x);
    return x;
}

/// Bits of the half nearest to x (ties to even).
std::uint16_t float_to_half(float x);
/// The float equal to the half with bits h (exact).
float half_to_float(std::uint16_t h);
/// x rounded to the nearest half, as a float.
inline float round_to_half(float x) { return half_to_float(float_to_half(x)); }

} // namespace lb::nn
