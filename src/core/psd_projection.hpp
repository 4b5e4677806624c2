#pragma once
// Projection of a symmetric matrix onto the PSD cone by eigenvalue clamping
// (Teran et al. 2005): H = Q Λ Qᵀ  ->  Q max(Λ, 0) Qᵀ.
#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace lb {

/// True if the symmetric matrix H is positive semi-definite up to round-off.
/// A pivoted LDLᵀ costs a fraction of an eigendecomposition; by Sylvester's law
/// of inertia, D has as many negative entries as H has negative eigenvalues.
template <typename Derived>
bool is_psd(const Eigen::MatrixBase<Derived>& H)
{
    using Matrix = typename Derived::PlainObject;
    const Eigen::LDLT<Matrix> ldlt(H);
    if (ldlt.info() != Eigen::Success) return false;
    const auto d = ldlt.vectorD();
    const double scale = std::max(d.cwiseAbs().maxCoeff(), 1e-300);
    return d.minCoeff() >= -1e-10 * scale;
}

/// @param H  symmetric matrix (only its lower triangle is read)
/// @return   the nearest PSD matrix in the Frobenius norm (H itself if already PSD)
template <typename Derived>
typename Derived::PlainObject project_psd(const Eigen::MatrixBase<Derived>& H)
{
    using Matrix = typename Derived::PlainObject;
    if (is_psd(H)) {
        return H;
    }
    Eigen::SelfAdjointEigenSolver<Matrix> eig(H);
    auto values = eig.eigenvalues();
    if (values.minCoeff() >= 0.0) {
        return H;
    }
    values = values.cwiseMax(0.0);
    return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

} // namespace lb
