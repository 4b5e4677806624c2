#pragma once
// Discrete curvature binormal of a rod vertex (Bergou et al. 2008) and its derivatives:
// the geometric core ("density level") of RodBending.
//
//   κb = 2 e0 × e1 / (|e0||e1| + e0·e1),  e0 = x_i − x_{i−1},  e1 = x_{i+1} − x_i,
//   |κb| = 2 tan(φ/2) with φ the turning angle between e0 and e1.
// Derivatives are taken with respect to z = (e0, e1) ∈ R⁶; the rod energy maps them to
// the three vertices.
#include <Eigen/Core>
#include <cmath>

#include "core/types.hpp"

namespace lb {

using Matrix36d = Eigen::Matrix<double, 3, 6>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// κb(e0, e1); if `jacobian` is non-null also ∂κb/∂(e0, e1) (3×6):
///   ∂κb/∂e0 = (−2[e1]× − κb (|e1| ê0 + e1)ᵀ) / d,   ∂κb/∂e1 = (2[e0]× − κb (|e0| ê1 + e0)ᵀ) / d,
/// with d = |e0||e1| + e0·e1 and [a]× the cross-product matrix (a × y = [a]× y).
Vector3d curvature_binormal(const Vector3d& e0, const Vector3d& e1, Matrix36d* jacobian = nullptr);

/// κb(e0, e1) and Jᵀ w = ∂(w·κb)/∂(e0, e1) for w = s κb (a multiple of κb itself, as in
/// the gradient of s/2 |κb|²), without forming J, on plain arrays (inlined into the SIMD
/// lanes of RodBending's pass, energy/element_lanes.hpp):
///   Jᵀw = ((2 e1 × w − (κb·w)(|e1| ê0 + e1)) / d,  (2 w × e0 − (κb·w)(|e0| ê1 + e0)) / d).
/// Returns |κb|²; writes κb to kb and Jᵀw to out (e0 part, then e1 part).
inline double curvature_binormal_vjp(const double (&e0)[3], const double (&e1)[3], double s, double (&kb)[3],
                                     double (&out)[6])
{
    const double l0 = std::sqrt(e0[0] * e0[0] + e0[1] * e0[1] + e0[2] * e0[2]);
    const double l1 = std::sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    const double inv_d = 1.0 / (l0 * l1 + e0[0] * e1[0] + e0[1] * e1[1] + e0[2] * e1[2]);
    kb[0] = 2.0 * (e0[1] * e1[2] - e0[2] * e1[1]) * inv_d;
    kb[1] = 2.0 * (e0[2] * e1[0] - e0[0] * e1[2]) * inv_d;
    kb[2] = 2.0 * (e0[0] * e1[1] - e0[1] * e1[0]) * inv_d;
    const double kk = kb[0] * kb[0] + kb[1] * kb[1] + kb[2] * kb[2];
    const double w[3] = {s * kb[0], s * kb[1], s * kb[2]};
    const double kw = s * kk, r01 = l1 / l0, r10 = l0 / l1;
    out[0] = (2.0 * (e1[1] * w[2] - e1[2] * w[1]) - kw * (r01 * e0[0] + e1[0])) * inv_d;
    out[1] = (2.0 * (e1[2] * w[0] - e1[0] * w[2]) - kw * (r01 * e0[1] + e1[1])) * inv_d;
    out[2] = (2.0 * (e1[0] * w[1] - e1[1] * w[0]) - kw * (r01 * e0[2] + e1[2])) * inv_d;
    out[3] = (2.0 * (w[1] * e0[2] - w[2] * e0[1]) - kw * (r10 * e1[0] + e0[0])) * inv_d;
    out[4] = (2.0 * (w[2] * e0[0] - w[0] * e0[2]) - kw * (r10 * e1[1] + e0[1])) * inv_d;
    out[5] = (2.0 * (w[0] * e0[1] - w[1] * e0[0]) - kw * (r10 * e1[2] + e0[2])) * inv_d;
    return kk;
}

/// Σ_k w_k ∂²κb_k/∂(e0, e1)² (6×6, symmetric) for a fixed weight vector w: the
/// second-order part of the Hessian of any function of κb.
Matrix6d curvature_binormal_contracted_hessian(const Vector3d& e0, const Vector3d& e1, const Vector3d& w);

} // namespace lb
