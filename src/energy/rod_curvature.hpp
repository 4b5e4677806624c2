#pragma once
// Discrete curvature binormal of a rod vertex (Bergou et al. 2008) and its derivatives:
// the geometric core ("density level") of RodBending.
//
//   κb = 2 e0 × e1 / (|e0||e1| + e0·e1),  e0 = x_i − x_{i−1},  e1 = x_{i+1} − x_i,
//   |κb| = 2 tan(φ/2) with φ the turning angle between e0 and e1.
// Derivatives are taken with respect to z = (e0, e1) ∈ R⁶; the rod energy maps them to
// the three vertices.
#include <Eigen/Core>

#include "core/types.hpp"

namespace lb {

using Matrix36d = Eigen::Matrix<double, 3, 6>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// κb(e0, e1); if `jacobian` is non-null also ∂κb/∂(e0, e1) (3×6):
///   ∂κb/∂e0 = (−2[e1]× − κb (|e1| ê0 + e1)ᵀ) / d,   ∂κb/∂e1 = (2[e0]× − κb (|e0| ê1 + e0)ᵀ) / d,
/// with d = |e0||e1| + e0·e1 and [a]× the cross-product matrix (a × y = [a]× y).
Vector3d curvature_binormal(const Vector3d& e0, const Vector3d& e1, Matrix36d* jacobian = nullptr);

/// Jᵀ w = ∂(w·κb)/∂(e0, e1) (6) for a weight vector w, without forming J:
///   (2 e1 × w − (κb·w)(|e1| ê0 + e1)) / d,   (2 w × e0 − (κb·w)(|e0| ê1 + e0)) / d.
/// With w = κb it is half the gradient of |κb|² (RodBending's training pass).
/// `kb` is κb(e0, e1), which the caller has (e.g. from curvature_binormal without J).
Eigen::Matrix<double, 6, 1> curvature_binormal_vjp(const Vector3d& e0, const Vector3d& e1, const Vector3d& kb,
                                                   const Vector3d& w);

/// Σ_k w_k ∂²κb_k/∂(e0, e1)² (6×6, symmetric) for a fixed weight vector w: the
/// second-order part of the Hessian of any function of κb.
Matrix6d curvature_binormal_contracted_hessian(const Vector3d& e0, const Vector3d& e1, const Vector3d& w);

} // namespace lb
