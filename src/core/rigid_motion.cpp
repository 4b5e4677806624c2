#include "core/rigid_motion.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>

namespace lb {

Matrix3d kabsch_rotation(const Matrix3d& H)
{
    const Eigen::JacobiSVD<Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    // A rotation about the line through collinear points is undetermined (the SVD
    // completes it arbitrarily): no rotation.
    constexpr double kCollinear = 1e-9;
    const Vector3d sigma = svd.singularValues();
    if (!(sigma[1] > kCollinear * sigma[0])) return Matrix3d::Identity();
    Matrix3d correction = Matrix3d::Identity();
    if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) correction(2, 2) = -1.0;
    return svd.matrixV() * correction * svd.matrixU().transpose();
}

RigidMotion fit_rigid_motion(const MatrixX3d& from, const MatrixX3d& to)
{
    RigidMotion m;
    if (from.rows() == 0) return m;
    m.from_centroid = from.colwise().mean().transpose();
    m.to_centroid = to.colwise().mean().transpose();
    const MatrixX3d p = from.rowwise() - m.from_centroid.transpose();
    const MatrixX3d q = to.rowwise() - m.to_centroid.transpose();
    m.rotation = kabsch_rotation(p.transpose() * q);  // collinear: the translation only
    return m;
}

} // namespace lb
