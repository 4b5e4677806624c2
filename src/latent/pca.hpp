#pragma once
// Principal component analysis of a set of feature vectors (columns), used to
// initialise the autoencoder's outer layers (Fulton et al. 2019) and available to
// linear-subspace baselines.
//
// With C = X − μ1ᵀ (F × S, centred), the basis U (F × d) holds the d leading left
// singular vectors of C, i.e. eigenvectors of C Cᵀ. Computed from whichever Gram
// matrix is smaller:
//   S ≤ F:  CᵀC = V Λ Vᵀ (S × S),  U = C V Λ^{-1/2}, then re-orthonormalised by a
//           Householder QR (columns kept in order, signs so that diag R > 0) because
//           forming CᵀC squares the condition number; directions with λ ≤ 1e-12 λ_max
//           carry no variance and are completed to an orthonormal set.
//   S > F:  C Cᵀ = U Λ Uᵀ (F × F) directly.
// Each column's sign is fixed so that its largest-magnitude entry is positive.
#include "core/types.hpp"

namespace lb {

/// Relative eigenvalue (variance) below which a direction counts as carrying none.
inline constexpr double kPcaRankTolerance = 1e-12;

struct PcaBasis {
    VectorXd mean;       ///< F, μ
    MatrixXd basis;      ///< F × d, orthonormal columns, by decreasing variance
    VectorXd variances;  ///< d, λ_i / S (population variance along each direction)
    double total_variance = 0.0;  ///< ||C||_F² / S
    /// Numerical rank of C: the directions with λ > kPcaRankTolerance · λ_max (of all
    /// min(F, S) directions, not only the d computed). Columns of `basis` past it carry no
    /// variance: they are an arbitrary orthonormal completion.
    Index rank = 0;

    Index dim() const { return basis.cols(); }
    /// Fraction of the total variance captured by the d directions (1 if there is none).
    double explained_fraction() const;
};

/// @param X    F × S data, one sample per column (S ≥ 1)
/// @param dim  number of directions d, 1 ≤ d ≤ F (directions beyond the data's rank have zero variance)
PcaBasis compute_pca(const MatrixXd& X, Index dim);

} // namespace lb
