#include "core/rigid_motion.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>

namespace lb {

namespace {

/// Points whose second singular value is at most this fraction of the first are collinear:
/// a rotation about their line is undetermined.
constexpr double kCollinear = 1e-9;

} // namespace

Matrix3d kabsch_rotation(const Matrix3d& H)
{
    const Eigen::JacobiSVD<Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
    // A rotation about the line through collinear points is undetermined (the SVD
    // completes it arbitrarily): no rotation.
    const Vector3d sigma = svd.singularValues();
    if (!(sigma[1] > kCollinear * sigma[0])) return Matrix3d::Identity();
    Matrix3d correction = Matrix3d::Identity();
    if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) correction(2, 2) = -1.0;
    return svd.matrixV() * correction * svd.matrixU().transpose();
}

RestFrame::RestFrame(const Eigen::Ref<const VectorXd>& rest)
    : m_offsets(Eigen::Map<const Eigen::Matrix3Xd>(rest.data(), 3, rest.size() / 3))
{
    if (m_offsets.cols() > 0) m_offsets.colwise() -= m_offsets.rowwise().mean();
}

bool RestFrame::fixes_rotation() const
{
    if (m_offsets.cols() < 3) return false;
    const Vector3d s = Eigen::JacobiSVD<Matrix3d>(m_offsets * m_offsets.transpose()).singularValues();
    return s[1] > kCollinear * s[0];
}

Matrix3d RestFrame::rotation(const double* p) const
{
    // H = Σ_k (p⁰_k − c⁰)(p_k − c)ᵀ = Σ_k (p⁰_k − c⁰) p_kᵀ (the rest offsets sum to zero).
    Matrix3d H = Matrix3d::Zero();
    for (Index k = 0; k < m_offsets.cols(); ++k)
        H.noalias() += m_offsets.col(k) * Eigen::Map<const Vector3d>(p + 3 * k).transpose();
    return kabsch_rotation(H);
}

Vector3d RestFrame::centroid(const double* p) const
{
    Vector3d c = Vector3d::Zero();
    for (Index k = 0; k < m_offsets.cols(); ++k) c += Eigen::Map<const Vector3d>(p + 3 * k);
    return m_offsets.cols() > 0 ? Vector3d(c / double(m_offsets.cols())) : c;
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
