#pragma once
// St. Venant–Kirchhoff: the density level shared by TetStVK (D = 3, solids) and
// ShellMembrane (D = 2, plane stress), and the linear-element chain rule that
// turns it into element gradients and Hessians.
//
// Density, for a deformation gradient F (3×D):
//   G = ½ (FᵀF − I)                         Green strain (D×D)
//   ψ = μ ||G||_F² + ½ λ (tr G)²            energy per unit reference measure
//   S = 2μ G + λ tr(G) I                    second Piola–Kirchhoff stress (D×D)
//   P = ∂ψ/∂F = F S                         first Piola–Kirchhoff stress (3×D)
//   ∂P_ij/∂F_mn = δ_im S_nj + μ F_in F_mj + μ δ_jn (FFᵀ)_im + λ F_ij F_mn
//
// Linear element with K = D + 1 vertices: F = Σ_a x_a b_aᵀ, where b_a (a = 1..D) is
// row a−1 of Dm⁻¹ and b_0 = −Σ_{a≥1} b_a, Dm = [X_1 − X_0, …, X_D − X_0] in a
// D-dimensional rest frame. The element energy is E_e = V ψ(F) (V the rest measure).
//
// For D = 3 the file also gives the analytic eigensystem of ∂P/∂F and, from it, a
// cheap PSD projection of the element Hessian (see "Analytic eigensystem" below).
#include <Eigen/Core>
#include <array>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>

namespace lb {

/// Lamé parameters (Pa) of an isotropic solid.
struct LameParameters {
    double mu = 0.0;
    double lambda = 0.0;
};

/// 3D Lamé parameters: μ = E / (2(1+ν)), λ = E ν / ((1+ν)(1−2ν)).
inline LameParameters lame_parameters(double youngs, double poisson)
{
    return {youngs / (2.0 * (1.0 + poisson)),
            youngs * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))};
}

/// Plane-stress Lamé parameters: μ = E / (2(1+ν)), λ = E ν / (1−ν²). With them
/// μ||G||² + ½λ(tr G)² = k/(2t)·[(1−ν)||G||² + ν (tr G)²], k = E t/(1−ν²).
inline LameParameters plane_stress_lame_parameters(double youngs, double poisson)
{
    return {youngs / (2.0 * (1.0 + poisson)), youngs * poisson / (1.0 - poisson * poisson)};
}

template <int D>
using DeformationGradient = Eigen::Matrix<double, 3, D>;

/// G = ½ (FᵀF − I), D×D.
template <int D>
Eigen::Matrix<double, D, D> green_strain(const DeformationGradient<D>& F)
{
    return 0.5 * (F.transpose() * F - Eigen::Matrix<double, D, D>::Identity());
}

/// ψ = μ ||G||_F² + ½ λ (tr G)² of a Green strain G.
template <int D>
double stvk_psi_of_strain(const Eigen::Matrix<double, D, D>& G, const LameParameters& lame)
{
    const double tr = G.trace();
    return lame.mu * G.squaredNorm() + 0.5 * lame.lambda * tr * tr;
}

/// S = 2μ G + λ tr(G) I of a Green strain G (D×D, symmetric).
template <int D>
Eigen::Matrix<double, D, D> stvk_stress_of_strain(const Eigen::Matrix<double, D, D>& G, const LameParameters& lame)
{
    Eigen::Matrix<double, D, D> S = 2.0 * lame.mu * G;
    S.diagonal().array() += lame.lambda * G.trace();
    return S;
}

/// ψ(F) = μ ||G||_F² + ½ λ (tr G)².
template <int D>
double stvk_psi(const DeformationGradient<D>& F, const LameParameters& lame)
{
    return stvk_psi_of_strain<D>(green_strain<D>(F), lame);
}

/// S = 2μ G + λ tr(G) I (D×D, symmetric).
template <int D>
Eigen::Matrix<double, D, D> stvk_second_piola(const DeformationGradient<D>& F, const LameParameters& lame)
{
    return stvk_stress_of_strain<D>(green_strain<D>(F), lame);
}

/// P = ∂ψ/∂F = F S (3×D).
template <int D>
DeformationGradient<D> stvk_first_piola(const DeformationGradient<D>& F, const LameParameters& lame)
{
    return F * stvk_second_piola<D>(F, lame);
}

/// ∂P/∂F as a 3D×3D matrix acting on vec(F) (column-major: F_mn at m + 3n).
/// Entry (i + 3j, m + 3n) = δ_im S_nj + μ F_in F_mj + μ δ_jn (FFᵀ)_im + λ F_ij F_mn.
/// Used to document and test the density; the element kernels below use the same
/// four terms without forming this matrix.
template <int D>
Eigen::Matrix<double, 3 * D, 3 * D> stvk_dPdF(const DeformationGradient<D>& F, const LameParameters& lame)
{
    const Eigen::Matrix<double, D, D> S = stvk_second_piola<D>(F, lame);
    const Eigen::Matrix3d FFt = F * F.transpose();
    Eigen::Matrix<double, 3 * D, 3 * D> dPdF;
    for (int n = 0; n < D; ++n) {
        for (int m = 0; m < 3; ++m) {
            for (int j = 0; j < D; ++j) {
                for (int i = 0; i < 3; ++i) {
                    double v = lame.mu * F(i, n) * F(m, j) + lame.lambda * F(i, j) * F(m, n);
                    if (i == m) v += S(n, j);
                    if (j == n) v += lame.mu * FFt(i, m);
                    dPdF(i + 3 * j, m + 3 * n) = v;
                }
            }
        }
    }
    return dPdF;
}

/// F = Σ_a x_a b_aᵀ for a linear element.
/// @param xe  3K element positions, xyz interleaved
/// @param B   K×D shape-gradient rows b_a
template <int K, int D>
DeformationGradient<D> linear_deformation_gradient(const Eigen::Matrix<double, 3 * K, 1>& xe,
                                                   const Eigen::Matrix<double, K, D>& B)
{
    DeformationGradient<D> F = xe.template segment<3>(0) * B.row(0);
    for (int a = 1; a < K; ++a) F.noalias() += xe.template segment<3>(3 * a) * B.row(a);
    return F;
}

/// Element gradient g_a = V P b_a (3K).
template <int K, int D>
Eigen::Matrix<double, 3 * K, 1> stvk_element_gradient(const DeformationGradient<D>& F,
                                                      const Eigen::Matrix<double, K, D>& B,
                                                      double measure, const LameParameters& lame)
{
    const DeformationGradient<D> P = stvk_first_piola<D>(F, lame);
    const Eigen::Matrix<double, 3, K> PBt = measure * P * B.transpose();
    return Eigen::Map<const Eigen::Matrix<double, 3 * K, 1>>(PBt.data());
}

/// The parameters of a linear element for stvk_lane_value_gradient (ElementLanes): the K×D
/// shape gradients row by row (p[D a + d] = b_a(d)), then the rest measure V.
template <int K, int D>
std::array<double, K * D + 1> stvk_lane_params(const Eigen::Matrix<double, K, D>& B, double measure)
{
    std::array<double, K * D + 1> p{};
    for (int a = 0; a < K; ++a) {
        for (int d = 0; d < D; ++d) p[std::size_t(D * a + d)] = B(a, d);
    }
    p[K * D] = measure;
    return p;
}

/// E_e = V ψ(F) with its gradient g_a = V P b_a, the Green strain formed once for both, on
/// plain arrays: one SIMD lane of ElementLanes (the training losses' pass) or, through
/// ElementLanes::evaluate, one element (local_value_gradient).
/// p[j], j < K·D + 1: the shape gradients b_a (p[D a + d]) and the rest measure V (p[K D]).
template <int K, int D, typename Params>
inline double stvk_lane_value_gradient(const double (&x)[K][3], const Params& p,
                                       const LameParameters& lame, double (&g)[K][3])
{
    double F[3][D] = {};
    for (int a = 0; a < K; ++a) {
        for (int i = 0; i < 3; ++i) {
            for (int d = 0; d < D; ++d) F[i][d] += x[a][i] * p[D * a + d];
        }
    }
    double G[D][D];
    double trace = 0.0, squared = 0.0;
    for (int d = 0; d < D; ++d) {
        for (int e = 0; e < D; ++e) {
            double ftf = 0.0;
            for (int i = 0; i < 3; ++i) ftf += F[i][d] * F[i][e];
            G[d][e] = 0.5 * (ftf - (d == e ? 1.0 : 0.0));
            squared += G[d][e] * G[d][e];
        }
        trace += G[d][d];
    }
    const double v = p[K * D];
    double S[D][D];
    for (int d = 0; d < D; ++d) {
        for (int e = 0; e < D; ++e) S[d][e] = 2.0 * lame.mu * G[d][e] + (d == e ? lame.lambda * trace : 0.0);
    }
    double VP[3][D];
    for (int i = 0; i < 3; ++i) {
        for (int d = 0; d < D; ++d) {
            double sum = 0.0;
            for (int e = 0; e < D; ++e) sum += F[i][e] * S[e][d];
            VP[i][d] = v * sum;
        }
    }
    for (int a = 0; a < K; ++a) {
        for (int i = 0; i < 3; ++i) {
            double sum = 0.0;
            for (int d = 0; d < D; ++d) sum += VP[i][d] * p[D * a + d];
            g[a][i] = sum;
        }
    }
    return v * (lame.mu * squared + 0.5 * lame.lambda * trace * trace);
}

/// Element Hessian (3K×3K) of E_e = V ψ(F(x_e)), unprojected.
template <int K, int D>
Eigen::Matrix<double, 3 * K, 3 * K> stvk_element_hessian(const DeformationGradient<D>& F,
                                                         const Eigen::Matrix<double, K, D>& B,
                                                         double measure, const LameParameters& lame)
{
    // Chain rule. x_e ↦ F is linear, ∂F_ij/∂x_a,k = δ_ik b_a(j), so the 3×3 block
    //   H_ab(i,m) = V Σ_jn b_a(j) b_b(n) ∂P_ij/∂F_mn.
    // Substituting the four terms of ∂P/∂F and writing f_a = F b_a (3-vector):
    //   δ_im S_nj          -> (b_aᵀ S b_b) δ_im
    //   μ F_in F_mj        -> μ (f_b)_i (f_a)_m          = μ f_b f_aᵀ
    //   μ δ_jn (FFᵀ)_im    -> μ (b_a·b_b) (FFᵀ)_im
    //   λ F_ij F_mn        -> λ (f_a)_i (f_b)_m          = λ f_a f_bᵀ
    // so H_ab = V [ (b_aᵀSb_b) I + μ f_b f_aᵀ + μ (b_a·b_b) FFᵀ + λ f_a f_bᵀ ],
    // O(K²) 3×3 blocks instead of a (3K×3D)(3D×3D)(3D×3K) product. H_ba = H_abᵀ.
    const Eigen::Matrix<double, D, D> S = stvk_second_piola<D>(F, lame);
    const Eigen::Matrix3d FFt = measure * lame.mu * (F * F.transpose());
    const Eigen::Matrix<double, 3, K> f = F * B.transpose();
    const Eigen::Matrix<double, K, K> BSB = measure * (B * S * B.transpose());
    const Eigen::Matrix<double, K, K> BB = B * B.transpose();
    const double vmu = measure * lame.mu;
    const double vlambda = measure * lame.lambda;

    Eigen::Matrix<double, 3 * K, 3 * K> H;
    for (int b = 0; b < K; ++b) {
        for (int a = b; a < K; ++a) {
            Eigen::Matrix3d block = vmu * f.col(b) * f.col(a).transpose() +
                                    vlambda * f.col(a) * f.col(b).transpose() + BB(a, b) * FFt;
            block.diagonal().array() += BSB(a, b);
            H.template block<3, 3>(3 * a, 3 * b) = block;
            if (a != b) H.template block<3, 3>(3 * b, 3 * a) = block.transpose();
        }
    }
    return H;
}

// ---- Analytic eigensystem of ∂P/∂F (D = 3) and the PSD-projected element Hessian ----
//
// ψ is isotropic (a function of the invariants of FᵀF), so with the SVD F = U Σ Vᵀ
// (U, V orthogonal, Σ = diag(σ)) ψ(F) = ψ(Σ + Uᵀ dF V) to second order in the rotated
// frame, and ∂P/∂F is ∂P/∂F at the diagonal Σ conjugated by U ⊗ V (Teran et al. 2005;
// Smith et al. 2019, "Analytic eigensystems for isotropic distortion energies").
// Inserting F = Σ, S = diag(s), s_i = 2μ g_i + λ Σ_k g_k, g_i = (σ_i² − 1)/2, into the
// four terms of ∂P/∂F above (entry (ij, mn)):
//   * the three diagonal entries (F̂_00, F̂_11, F̂_22) couple only among themselves, through
//       A_im = δ_im (s_i + 2μ σ_i²) + λ σ_i σ_m = δ_im (3μ σ_i² + c) + λ σ_i σ_m
//     (= ∂²ψ̂/∂σ_i∂σ_m); its eigenvectors e give the "scaling" modes U diag(e) Vᵀ;
//   * each off-diagonal pair (F̂_ij, F̂_ji), i ≠ j, is a 2×2 block
//       [ μ(σ_i² + σ_j²) + c   μ σ_i σ_j          ]        c = λ Σ_k g_k − μ
//       [ μ σ_i σ_j            μ(σ_i² + σ_j²) + c ],
//     (δ_im S_nj gives s_j = μσ_j² + c, μ δ_jn (FFᵀ)_im gives μσ_i², μ F_in F_mj the
//     off-diagonal), with eigenpairs
//       flip   μ(σ_i² + σ_iσ_j + σ_j²) + c   on U (e_i e_jᵀ + e_j e_iᵀ) Vᵀ / √2,
//       twist  μ(σ_i² − σ_iσ_j + σ_j²) + c   on U (e_i e_jᵀ − e_j e_iᵀ) Vᵀ / √2.
// No formula divides by σ or by σ_i − σ_j, so repeated and zero singular values need no
// special case, and the identities hold for any orthogonal U, V (inverted elements too).
// At rest (σ = 1) the twists are 0 (rotations) and the flips 2μ; under compression the
// twists turn negative first, which is what makes StVK's Hessian indefinite.

namespace detail {

/// Principal axes (i, j) of flip/twist pair k: (1, 2), (2, 0), (0, 1).
inline int pair_first(int k) { return (k + 1) % 3; }
inline int pair_second(int k) { return (k + 2) % 3; }

/// c = λ Σ_k g_k − μ, the shift shared by A's diagonal and the pair eigenvalues.
inline double stvk_principal_shift(const Eigen::Vector3d& sigma, const LameParameters& lame)
{
    return lame.lambda * 0.5 * (sigma.squaredNorm() - 3.0) - lame.mu;
}

} // namespace detail

/// The 3×3 block A = ∂²ψ̂/∂σ² on the diagonal of the rotated F̂ (see above).
inline Eigen::Matrix3d stvk_scaling_block(const Eigen::Vector3d& sigma, const LameParameters& lame)
{
    Eigen::Matrix3d A = lame.lambda * sigma * sigma.transpose();
    A.diagonal() += 3.0 * lame.mu * sigma.cwiseAbs2() + Eigen::Vector3d::Constant(detail::stvk_principal_shift(sigma, lame));
    return A;
}

/// Flip (sign = +1) or twist (sign = −1) eigenvalues μ(σ_i² ± σ_iσ_j + σ_j²) + c, entry k
/// for the pair (i, j) = ((k+1) mod 3, (k+2) mod 3).
inline Eigen::Vector3d stvk_pair_values(const Eigen::Vector3d& sigma, const LameParameters& lame, double sign)
{
    const double c = detail::stvk_principal_shift(sigma, lame);
    Eigen::Vector3d values;
    for (int k = 0; k < 3; ++k) {
        const double si = sigma[detail::pair_first(k)], sj = sigma[detail::pair_second(k)];
        values[k] = lame.mu * (si * si + sign * si * sj + sj * sj) + c;
    }
    return values;
}

/// The nine eigenpairs of the 3D StVK ∂P/∂F:
///   ∂P/∂F = Σ_k λ_k vec(Q_k) vec(Q_k)ᵀ,   Q_k = U Q̂_k Vᵀ,   ⟨Q_k, Q_l⟩_F = δ_kl.
/// Modes k = 0..2 are the scaling modes, 3..5 the flips and 6..8 the twists of pairs 0..2.
struct StvkStressEigensystem {
    static constexpr int kModes = 9;
    Eigen::Matrix3d U;               ///< F = U diag(sigma) Vᵀ
    Eigen::Matrix3d V;
    Eigen::Vector3d sigma;           ///< singular values, ≥ 0
    Eigen::Vector3d scaling_values;  ///< eigenvalues of stvk_scaling_block
    Eigen::Matrix3d scaling_vectors; ///< their unit eigenvectors (columns)
    Eigen::Vector3d flip_values;     ///< stvk_pair_values(sigma, lame, +1)
    Eigen::Vector3d twist_values;    ///< stvk_pair_values(sigma, lame, −1)

    double value(int k) const
    {
        return k < 3 ? scaling_values[k] : k < 6 ? flip_values[k - 3] : twist_values[k - 6];
    }
    /// Q̂_k, the mode in the principal frame (3×3, unit Frobenius norm).
    Eigen::Matrix3d principal_mode(int k) const
    {
        if (k < 3) return Eigen::Matrix3d(scaling_vectors.col(k).asDiagonal());
        const int pair = k < 6 ? k - 3 : k - 6;
        const int i = detail::pair_first(pair), j = detail::pair_second(pair);
        Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
        Q(i, j) = std::sqrt(0.5);
        Q(j, i) = k < 6 ? std::sqrt(0.5) : -std::sqrt(0.5);
        return Q;
    }
    /// Q_k = U Q̂_k Vᵀ (3×3, unit Frobenius norm).
    Eigen::Matrix3d mode(int k) const { return U * principal_mode(k) * V.transpose(); }
};

/// Analytic eigensystem of ∂P/∂F (one 3×3 SVD and one 3×3 symmetric eigensolve).
inline StvkStressEigensystem stvk_stress_eigensystem(const Eigen::Matrix3d& F, const LameParameters& lame)
{
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    StvkStressEigensystem es;
    es.U = svd.matrixU();
    es.V = svd.matrixV();
    es.sigma = svd.singularValues();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> scaling(stvk_scaling_block(es.sigma, lame));
    es.scaling_values = scaling.eigenvalues();
    es.scaling_vectors = scaling.eigenvectors();
    es.flip_values = stvk_pair_values(es.sigma, lame, +1.0);
    es.twist_values = stvk_pair_values(es.sigma, lame, -1.0);
    return es;
}

/// (∂P/∂F)₊ = Σ_k max(λ_k, 0) vec(Q_k) vec(Q_k)ᵀ (9×9, same layout as stvk_dPdF): the
/// nearest PSD matrix to ∂P/∂F in the Frobenius norm, from the analytic eigensystem.
inline Eigen::Matrix<double, 9, 9> stvk_projected_dPdF(const Eigen::Matrix3d& F, const LameParameters& lame)
{
    const StvkStressEigensystem es = stvk_stress_eigensystem(F, lame);
    Eigen::Matrix<double, 9, 9> dPdF = Eigen::Matrix<double, 9, 9>::Zero();
    for (int k = 0; k < StvkStressEigensystem::kModes; ++k) {
        if (es.value(k) <= 0.0) continue;
        const Eigen::Matrix3d Q = es.mode(k);
        const Eigen::Map<const Eigen::Matrix<double, 9, 1>> q(Q.data());
        dPdF.noalias() += es.value(k) * q * q.transpose();
    }
    return dPdF;
}

/// PSD-projected element Hessian (3K×3K) of E_e = V ψ(F(x_e)) for a linear element in 3D
/// (F = Σ_a x_a b_aᵀ, B the K×3 rows b_a):
///   H₊ = V Jᵀ (∂P/∂F)₊ J,   J = ∂vec(F)/∂x_e (9×3K),
/// with (∂P/∂F)₊ the analytic clamp above. Properties:
///   * symmetric PSD (a congruence of a PSD matrix);
///   * equal to stvk_element_hessian when ∂P/∂F is PSD, which (J having full row rank 9
///     for a non-degenerate element) is exactly when the element Hessian is PSD;
///   * NOT the nearest PSD matrix to the element Hessian in the Frobenius norm (what
///     project_psd returns): clamping the 9×9 ∂P/∂F and clamping the 3K×3K Jᵀ(∂P/∂F)J
///     differ unless JJᵀ ∝ I. It is still a valid PSD model of the energy for Newton,
///     and costs one 3×3 SVD instead of a 3K×3K eigendecomposition (tets: ≈ 0.8 µs vs
///     5 µs per element, bench_energy BM_TetStVK_ElementHessian; the SVD is most of it).
template <int K>
Eigen::Matrix<double, 3 * K, 3 * K> stvk_element_projected_hessian(const Eigen::Matrix3d& F,
                                                                   const Eigen::Matrix<double, K, 3>& B,
                                                                   double measure, const LameParameters& lame)
{
    using ElementVector = Eigen::Matrix<double, 3 * K, 1>;
    using ModeGradient = Eigen::Matrix<double, 3, K>;
    Eigen::Matrix<double, 3 * K, 3 * K> H = stvk_element_hessian<K, 3>(F, B, measure, lame);

    // Shortcut without an SVD: d²ψ[dF, dF] = S : (dFᵀdF) + 2μ ||sym(FᵀdF)||² + λ (tr FᵀdF)²,
    // so with λ ≥ 0 a positive definite S (Sylvester's leading minors) makes ∂P/∂F PSD.
    const Eigen::Matrix3d S = stvk_second_piola<3>(F, lame);
    if (lame.lambda >= 0.0 && S(0, 0) > 0.0 && S(0, 0) * S(1, 1) - S(0, 1) * S(0, 1) > 0.0 &&
        S.determinant() > 0.0) {
        return H;
    }

    // H = V Σ_k λ_k w_k w_kᵀ with w_k = Jᵀ vec(Q_k) = vec(Q_k Bᵀ) (node a's block is Q_k b_a),
    // so H₊ = H − V Σ_{λ_k < 0} λ_k w_k w_kᵀ touches only the (few) negative modes. In the
    // principal frame Q_k Bᵀ = U Q̂_k (B V)ᵀ: outer products of columns of U and of B V.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d& U = svd.matrixU();
    const Eigen::Vector3d& sigma = svd.singularValues();
    const Eigen::Matrix<double, K, 3> BV = B * svd.matrixV();
    auto remove_mode = [&](double value, const ModeGradient& QBt) {
        const Eigen::Map<const ElementVector> w(QBt.data());
        H.noalias() -= (measure * value) * w * w.transpose();
    };

    const double half_sqrt2 = std::sqrt(0.5);
    const Eigen::Vector3d flip = stvk_pair_values(sigma, lame, +1.0);
    const Eigen::Vector3d twist = stvk_pair_values(sigma, lame, -1.0);
    for (int k = 0; k < 3; ++k) {
        const int i = detail::pair_first(k), j = detail::pair_second(k);
        if (twist[k] < 0.0) {
            remove_mode(twist[k], half_sqrt2 * (U.col(i) * BV.col(j).transpose() - U.col(j) * BV.col(i).transpose()));
        }
        if (flip[k] < 0.0) {
            remove_mode(flip[k], half_sqrt2 * (U.col(i) * BV.col(j).transpose() + U.col(j) * BV.col(i).transpose()));
        }
    }

    // A = diag(d) + λ σσᵀ, d_i = 3μσ_i² + c, is PSD when d ≥ 0 and λ ≥ 0; otherwise decompose it.
    const double min_d = 3.0 * lame.mu * sigma.cwiseAbs2().minCoeff() + detail::stvk_principal_shift(sigma, lame);
    if (!(lame.lambda >= 0.0 && min_d >= 0.0)) {
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> scaling(stvk_scaling_block(sigma, lame));
        for (int k = 0; k < 3; ++k) {
            if (scaling.eigenvalues()[k] < 0.0) {
                remove_mode(scaling.eigenvalues()[k],
                            U * scaling.eigenvectors().col(k).asDiagonal() * BV.transpose());
            }
        }
    }
    return H;
}

} // namespace lb
