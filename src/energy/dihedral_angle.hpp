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
#include <cmath>

#include "core/lane_math.hpp"
#include "core/types.hpp"

namespace lb {

using HingeVector = Eigen::Matrix<double, 12, 1>;
using HingeMatrix = Eigen::Matrix<double, 12, 12>;

/// θ ∈ (−π, π] of the hinge whose positions are xe = (x0, x1, x2, x3) (12, xyz interleaved).
double dihedral_angle(const HingeVector& xe);

/// θ with ∂θ/∂xe (12) and, if `hessian` is non-null, ∂²θ/∂xe² (12×12, symmetric).
/// Undefined for a degenerate hinge (zero-area triangle or zero-length edge).
double dihedral_angle(const HingeVector& xe, HingeVector* gradient, HingeMatrix* hessian);

/// θ and ∂θ/∂x_a (written to g[a]) of the hinge x[0..3] on plain arrays, θ by lane_atan2: the
/// gradient-only route of dihedral_angle (derivation in dihedral_angle.cpp), in a form that
/// vectorises across hinges (ShellHingeBending's training pass inlines it into SIMD lanes).
inline double dihedral_angle_gradient(const double (&x)[4][3], double (&g)[4][3])
{
    double e[3], u[3], v[3];
    for (int i = 0; i < 3; ++i) {
        e[i] = x[1][i] - x[0][i];
        u[i] = x[2][i] - x[0][i];
        v[i] = x[3][i] - x[0][i];
    }
    const double n1[3] = {e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0]};
    const double n2[3] = {v[1] * e[2] - v[2] * e[1], v[2] * e[0] - v[0] * e[2], v[0] * e[1] - v[1] * e[0]};
    auto dot = [](const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
    const double ee = dot(e, e);
    const double len = std::sqrt(ee);
    const double theta = lane_atan2(-len * dot(n1, v), dot(n1, n2));
    // Two divisions instead of four (the lane loop is bound by the divider): 1/|N1|² and
    // 1/|N2|² from 1/(|N1|²|N2|²), 1/|e|² once.
    const double nn1 = dot(n1, n1), nn2 = dot(n2, n2);
    const double inv_nn = 1.0 / (nn1 * nn2);
    const double inv_ee = 1.0 / ee;
    const double s2 = -len * nn2 * inv_nn;
    const double s3 = -len * nn1 * inv_nn;
    const double t2 = dot(u, e) * inv_ee;
    const double t3 = dot(v, e) * inv_ee;
    for (int i = 0; i < 3; ++i) {
        const double g2 = s2 * n1[i], g3 = s3 * n2[i];
        g[0][i] = (t2 - 1.0) * g2 + (t3 - 1.0) * g3;
        g[1][i] = -t2 * g2 - t3 * g3;
        g[2][i] = g2;
        g[3][i] = g3;
    }
    return theta;
}

/// Wrap an angle difference into (−π, π] when it lies in (−3π, 3π], as the difference of two
/// angles in [−π, π] (θ − θ̄ of a hinge) does: one conditional shift each way, no fmod, so it
/// stays inside vectorised lane loops.
inline double wrap_angle_difference(double angle)
{
    constexpr double kPi = 3.14159265358979323846;
    angle = angle > kPi ? angle - 2.0 * kPi : angle;
    return angle <= -kPi ? angle + 2.0 * kPi : angle;
}

/// Wrap any angle into (−π, π].
double wrap_angle(double angle);

} // namespace lb
