#pragma once
// The signed dihedral angle of a hinge and its first and second derivatives: the
// geometric core ("density level") of ShellHingeBending.
//
// Hinge (x0, x1, x2, x3): shared edge x0–x1; x2 opposite in the triangle (x0, x1, x2),
// x3 opposite in the triangle (x1, x0, x3) (mesh/mesh.hpp stencil convention). With
//   e = x1 − x0, u = x2 − x0, v = x3 − x0,  N1 = e × u,  N2 = v × e  (triangle normals),
//   θ = atan2((n1 × n2)·ê, n1·n2),  n = N/|N|,  ê = e/|e|;   θ = 0 when flat.
// Because atan2 is invariant to a common positive scale of its arguments and
//   N1 × N2 = −det(e, u, v) e,   N1·N2 = (e·u)(e·v) − |e|² (u·v)   (Binet–Cauchy),
// θ = atan2(Y, X) with the polynomial-like
//   Y = −|e| det(e, u, v),   X = (e·u)(e·v) − |e|² (u·v),
// which makes exact first and second derivatives short (see dihedral_angle.cpp).
#include <Eigen/Core>

#include "core/types.hpp"

namespace lb {

using HingeVector = Eigen::Matrix<double, 12, 1>;
using HingeMatrix = Eigen::Matrix<double, 12, 12>;

/// θ ∈ (−π, π] of the hinge whose positions are xe = (x0, x1, x2, x3) (12, xyz interleaved).
double dihedral_angle(const HingeVector& xe);

/// θ with ∂θ/∂xe (12) and, if `hessian` is non-null, ∂²θ/∂xe² (12×12, symmetric).
/// Undefined for a degenerate hinge (zero-area triangle or zero-length edge).
double dihedral_angle(const HingeVector& xe, HingeVector* gradient, HingeMatrix* hessian);

/// Wrap an angle difference into (−π, π].
double wrap_angle(double angle);

} // namespace lb
