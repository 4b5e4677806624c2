#pragma once
// Plane-stress St. Venant–Kirchhoff membrane of a triangle shell (discrete shells).
//
//   density   ψ = k/2 [(1−ν) ||G||_F² + ν (tr G)²],  k = E t / (1−ν²)
//             = t [μ ||G||_F² + ½ λ_ps (tr G)²],  μ = E/(2(1+ν)), λ_ps = E ν/(1−ν²)
//   element   E_f = A_f ψ(F_f), G = ½ (FᵀF − I) (2×2), F = Ds Dm⁻¹ (3×2) the map from the
//             rest triangle's own orthonormal 2D frame, Ds = [x1−x0, x2−x0]
//   mesh      E = Σ_f E_f
//
// The density is the D = 2 case of energy/stvk_density.hpp with the plane-stress Lamé
// parameters, scaled by the thickness t.
#include <vector>

#include "energy/energy.hpp"
#include "energy/stvk_density.hpp"
#include "energy/stvk_lanes.hpp"

namespace lb {

class ShellMembrane final : public ElementEnergy<3> {

public:
    using ShapeGradients = Eigen::Matrix<double, 3, 2>;

    /// @param rest       N×3 rest positions (m)
    /// @param triangles  F×3 vertex indices (non-degenerate at rest)
    /// @param youngs     Young's modulus E (Pa)
    /// @param poisson    Poisson ratio ν ∈ (−1, 0.5)
    /// @param thickness  shell thickness t (m)
    ShellMembrane(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& triangles,
                  double youngs, double poisson, double thickness);

    std::string name() const override { return "shell_membrane"; }
    /// The serial pass (inside the training losses' batch loop) vectorised across elements
    /// (energy/stvk_lanes.hpp); the parallel pass is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;
    bool has_column_pass() const override { return true; }
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const override;

    /// Rest area A_f (m²).
    double rest_area(Index f) const { return m_areas[size_t(f)]; }
    /// Plane-stress Lamé parameters scaled by the thickness (N/m).
    const LameParameters& lame() const { return m_lame; }
    /// 3×2 deformation gradient of triangle f at the gathered positions (9).
    Eigen::Matrix<double, 3, 2> deformation_gradient(Index f, const ElementVector& xe) const;

protected:
    double local_value(Index f, const ElementVector& xe) const override;
    ElementVector local_gradient(Index f, const ElementVector& xe) const override;
    double local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const override;
    ElementMatrix local_hessian(Index f, const ElementVector& xe) const override;

private:
    LameParameters m_lame; // plane-stress μ, λ_ps times t
    std::vector<ShapeGradients> m_shape_gradients;
    std::vector<double> m_areas;
    StvkLanes<3, 2> m_lanes;  ///< the same elements, blocked for add_value_gradient
};

} // namespace lb
