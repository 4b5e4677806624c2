#include "energy/rod_curvature.hpp"

#include <Eigen/Geometry>

namespace lb {
namespace {
Matrix3d skew(const Vector3d& a)
{
    Matrix3d m;
    m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
    return m;
}
} // namespace

Vector3d curvature_binormal(const Vector3d& e0, const Vector3d& e1, Matrix36d* jacobian)
{
    const double l0 = e0.norm(), l1 = e1.norm();
    const double d = l0 * l1 + e0.dot(e1);
    const Vector3d kb = 2.0 * e0.cross(e1) / d;
    if (jacobian != nullptr) {
        // κb = 2n/d with n = e0 × e1:  ∂n/∂e0 = −[e1]×, ∂n/∂e1 = [e0]×,
        // ∂d/∂e0 = |e1| ê0 + e1, ∂d/∂e1 = |e0| ê1 + e0;  ∂κb = (2 ∂n − κb ∂dᵀ) / d.
        jacobian->leftCols<3>() = (-2.0 * skew(e1) - kb * (l1 / l0 * e0 + e1).transpose()) / d;
        jacobian->rightCols<3>() = (2.0 * skew(e0) - kb * (l0 / l1 * e1 + e0).transpose()) / d;
    }
    return kb;
}

Matrix6d curvature_binormal_contracted_hessian(const Vector3d& e0, const Vector3d& e1, const Vector3d& w)
{
    // f = w·κb = 2p/d with p = w·(e0 × e1), d = |e0||e1| + e0·e1. Chain rule:
    //   ∇²f = 2∇²p/d − 2(∇p ∇dᵀ + ∇d ∇pᵀ)/d² + 4p ∇d ∇dᵀ/d³ − 2p ∇²d/d²
    // with, over z = (e0, e1):
    //   ∇p = (e1 × w, w × e0);  ∇²p: ∂²/∂e0∂e1 = −[w]×, diagonal blocks 0
    //   ∇d = (|e1| ê0 + e1, |e0| ê1 + e0)
    //   ∇²d: ∂²/∂e0² = |e1| (I − ê0ê0ᵀ)/|e0|,  ∂²/∂e1² = |e0| (I − ê1ê1ᵀ)/|e1|,
    //        ∂²/∂e0∂e1 = ê0 ê1ᵀ + I
    const Matrix3d I = Matrix3d::Identity();
    const double l0 = e0.norm(), l1 = e1.norm();
    const Vector3d t0 = e0 / l0, t1 = e1 / l1;
    const double d = l0 * l1 + e0.dot(e1);
    const double p = w.dot(e0.cross(e1));

    Eigen::Matrix<double, 6, 1> grad_p, grad_d;
    grad_p << e1.cross(w), w.cross(e0);
    grad_d << l1 * t0 + e1, l0 * t1 + e0;

    Matrix6d hess_p = Matrix6d::Zero();
    hess_p.block<3, 3>(0, 3) = -skew(w);
    hess_p.block<3, 3>(3, 0) = skew(w);
    Matrix6d hess_d;
    hess_d.block<3, 3>(0, 0) = (l1 / l0) * (I - t0 * t0.transpose());
    hess_d.block<3, 3>(3, 3) = (l0 / l1) * (I - t1 * t1.transpose());
    hess_d.block<3, 3>(0, 3) = t0 * t1.transpose() + I;
    hess_d.block<3, 3>(3, 0) = t1 * t0.transpose() + I;

    const double d2 = d * d;
    Matrix6d H = (2.0 / d) * hess_p - (2.0 / d2) * (grad_p * grad_d.transpose() + grad_d * grad_p.transpose()) +
                 (4.0 * p / (d2 * d)) * grad_d * grad_d.transpose() - (2.0 * p / d2) * hess_d;
    return H;
}

} // namespace lb
