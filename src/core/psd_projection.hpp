#pragma once
// Projection of a symmetric matrix onto the PSD cone by eigenvalue clamping
// (Teran et al. 2005): H = Q Λ Qᵀ  ->  Q max(Λ, 0) Qᵀ.
#include <Eigen/Eigenvalues>

namespace lb {

/// @param H  symmetric matrix (only its lower triangle is read)
/// @return   the nearest PSD matrix in the Frobenius norm
template <typename Derived>
typename Derived::PlainObject project_psd(const Eigen::MatrixBase<Derived>& H)
{
    using Matrix = typename Derived::PlainObject;
    Eigen::SelfAdjointEigenSolver<Matrix> eig(H);
    auto values = eig.eigenvalues();
    if (values.minCoeff() >= 0.0) {
        return H;
    }
    values = values.cwiseMax(0.0);
    return eig.eigenvectors() * values.asDiagonal() * eig.eigenvectors().transpose();
}

} // namespace lb
