#pragma once
// Elementary functions written so that a loop over SIMD lanes vectorises them: no calls, no
// branches (selects only), no tables. The element kernels of energy/element_lanes.hpp run
// one element per lane; a libm call inside such a loop (std::atan2) keeps the whole loop
// scalar. std::sqrt is fine there (one instruction; the build passes -fno-math-errno).
#include <cmath>

namespace lb {

/// atan2(y, x) ∈ [−π, π] to a few ulp of std::atan2 (tests/core/test_lane_math.cpp checks
/// ≤ 4 ulp relative or 4e-16 absolute on random and special inputs), branch-free.
/// atan2(±0, ±0) is 0 here (std::atan2 gives ±0 or ±π); NaN in gives NaN out.
///
/// Reduction: t = min(|x|, |y|) / max(|x|, |y|) ∈ [0, 1] (the octant);
/// if t > tan(π/8), atan t = π/4 + atan((t − 1)/(t + 1)), leaving |t| ≤ tan(π/8) (computed
/// as (min − max)/(min + max), so the reduction costs one division);
/// the half-angle identity atan t = 2 atan(t / (1 + √(1 + t²))) leaves |t| ≤ tan(π/16);
/// there the Taylor series atan t = Σ_k (−1)^k t^(2k+1)/(2k+1) to k = 10 has a relative
/// truncation error below tan(π/16)^22 / 23 < 2e-17.
inline double lane_atan2(double y, double x)
{
    constexpr double kPi = 3.14159265358979323846;
    constexpr double kTanPi8 = 0.41421356237309504880;  // √2 − 1
    const double ax = std::abs(x), ay = std::abs(y);
    const bool swap = ay > ax;
    const double num = swap ? ax : ay;
    const double den = swap ? ay : ax;
    // t = num / den, or (t − 1)/(t + 1) = (num − den)/(num + den) past tan(π/8): one division
    // either way (den ≥ num ≥ 0, so the shift's denominator is 0 only when both are).
    const bool shift = num > kTanPi8 * den;
    const double n = shift ? num - den : num;
    const double d = shift ? num + den : den;
    double t = d == 0.0 ? 0.0 : n / d;  // NaN stays NaN
    t = t / (1.0 + std::sqrt(1.0 + t * t));
    const double s = t * t;
    // Horner over s of Σ_{k=0}^{10} (−1)^k s^k / (2k+1).
    double p = -1.0 / 21.0;
    p = p * s + 1.0 / 19.0;
    p = p * s - 1.0 / 17.0;
    p = p * s + 1.0 / 15.0;
    p = p * s - 1.0 / 13.0;
    p = p * s + 1.0 / 11.0;
    p = p * s - 1.0 / 9.0;
    p = p * s + 1.0 / 7.0;
    p = p * s - 1.0 / 5.0;
    p = p * s + 1.0 / 3.0;
    p = p * s;  // now Σ_{k=1}^{10} (−1)^(k+1) s^k/(2k+1), so atan t = t (1 − p)
    double a = 2.0 * (t - t * p);
    a = shift ? 0.25 * kPi + a : a;
    a = swap ? 0.5 * kPi - a : a;
    a = x < 0.0 ? kPi - a : a;
    return std::copysign(a, y);
}

} // namespace lb
