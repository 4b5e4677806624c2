#pragma once
// St. Venant–Kirchhoff linear tetrahedra: the elastic energy of solids.
//
//   density   ψ(F) = μ ||G||_F² + ½ λ (tr G)²,  G = ½ (FᵀF − I)   (energy/stvk_density.hpp)
//   element   E_t = V_t ψ(F_t),  F_t = Ds Dm⁻¹,  Ds = [x1−x0, x2−x0, x3−x0], Dm the same at rest
//   mesh      E = Σ_t E_t  (summed and assembled by the shared Energy / HessianAssembler)
//
// Lamé parameters from Young's modulus E and Poisson ratio ν:
//   μ = E / (2(1+ν)),  λ = E ν / ((1+ν)(1−2ν)).
// Dm⁻¹ (as the 4×3 shape-gradient matrix B) and V_t are precomputed; this is the hot kernel
// of the solid scenes, so the element Hessian is formed blockwise from the structure of ∂P/∂F.
//
// PSD projection (Newton's fallback) clamps the analytic eigensystem of the 9×9 ∂P/∂F
// (one 3×3 SVD; stvk_element_projected_hessian) instead of eigendecomposing the 12×12
// element Hessian: H₊ = V Jᵀ (∂P/∂F)₊ J, J = ∂vec(F)/∂x_e. The result is PSD and equals the
// exact Hessian whenever that is PSD, but it is not the nearest PSD matrix to the element
// Hessian in the Frobenius norm (which the generic ElementEnergy projection would give).
#include <vector>

#include "energy/energy.hpp"
#include "energy/stvk_density.hpp"
#include "energy/stvk_lanes.hpp"

namespace lb {

class TetStVK final : public ElementEnergy<4> {
public:
    using ShapeGradients = Eigen::Matrix<double, 4, 3>;

    /// @param rest     N×3 rest positions (m)
    /// @param tets     T×4 vertex indices; rest volume must be positive (det Dm > 0)
    /// @param youngs   Young's modulus E (Pa)
    /// @param poisson  Poisson ratio ν ∈ (−1, 0.5)
    /// @throws Error on bad indices, parameters, or an inverted/degenerate rest tetrahedron
    TetStVK(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& tets,
            double youngs, double poisson);

    std::string name() const override { return "tet_stvk"; }
    /// The serial pass (inside the training losses' batch loop) vectorised across elements
    /// (energy/stvk_lanes.hpp); the parallel pass is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;
    bool has_column_pass() const override { return true; }
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const override;

    const LameParameters& lame() const { return m_lame; }
    /// Rest volume V_t (m³).
    double rest_volume(Index t) const { return m_volumes[size_t(t)]; }
    /// 4×3 shape gradients of tet t: F = Σ_a x_a b_aᵀ with b_a = row a.
    const ShapeGradients& shape_gradients(Index t) const { return m_shape_gradients[size_t(t)]; }
    /// Deformation gradient F_t at the gathered element positions (12).
    Matrix3d deformation_gradient(Index t, const ElementVector& xe) const;

protected:
    double local_value(Index t, const ElementVector& xe) const override;
    ElementVector local_gradient(Index t, const ElementVector& xe) const override;
    double local_value_gradient(Index t, const ElementVector& xe, ElementVector& g) const override;
    ElementMatrix local_hessian(Index t, const ElementVector& xe) const override;
    ElementMatrix local_projected_hessian(Index t, const ElementVector& xe) const override;

private:
    LameParameters m_lame;
    std::vector<ShapeGradients> m_shape_gradients;
    std::vector<double> m_volumes;
    StvkLanes<4, 3> m_lanes;  ///< the same elements, blocked for add_value_gradient
};

} // namespace lb
