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
#include <Eigen/Core>

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

/// ψ(F) = μ ||G||_F² + ½ λ (tr G)².
template <int D>
double stvk_psi(const DeformationGradient<D>& F, const LameParameters& lame)
{
    const Eigen::Matrix<double, D, D> G = green_strain<D>(F);
    const double tr = G.trace();
    return lame.mu * G.squaredNorm() + 0.5 * lame.lambda * tr * tr;
}

/// S = 2μ G + λ tr(G) I (D×D, symmetric).
template <int D>
Eigen::Matrix<double, D, D> stvk_second_piola(const DeformationGradient<D>& F, const LameParameters& lame)
{
    const Eigen::Matrix<double, D, D> G = green_strain<D>(F);
    Eigen::Matrix<double, D, D> S = 2.0 * lame.mu * G;
    S.diagonal().array() += lame.lambda * G.trace();
    return S;
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

} // namespace lb
