#pragma once
// Discrete-shells hinge bending (Grinspun et al. 2003) over the interior edges.
//
//   density   per hinge: k_b (θ − θ̄)²,  k_b = E t³ / (24 (1−ν²))
//   element   E_h = w_h (θ − θ̄)²,  w_h = 3 k_b |ē|² / (Ā₁ + Ā₂)
//             θ the signed dihedral angle atan2((n₁×n₂)·ê, n₁·n₂) (energy/dihedral_angle.hpp),
//             θ̄, |ē|, Ā₁, Ā₂ the rest angle, edge length and the two triangle areas
//   mesh      E = Σ_h E_h
//
// Hinge stencil (M×4, mesh/mesh.hpp): (v0, v1) the shared edge, v2 opposite in the
// triangle containing the directed edge v0→v1, v3 opposite in the other. θ − θ̄ is
// wrapped into (−π, π]. This k_b is not calibrated to Koiter's energy (DESIGN §3).
#include <vector>

#include "energy/dihedral_angle.hpp"
#include "energy/element_lanes.hpp"
#include "energy/energy.hpp"

namespace lb {

class ShellHingeBending final : public ElementEnergy<4> {
public:
    /// @param rest       N×3 rest positions (m)
    /// @param hinges     M×4 hinge stencils (v0, v1, v2, v3)
    /// @param youngs     Young's modulus E (Pa)
    /// @param poisson    Poisson ratio ν ∈ (−1, 0.5)
    /// @param thickness  shell thickness t (m)
    ShellHingeBending(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& hinges,
                      double youngs, double poisson, double thickness);

    std::string name() const override { return "shell_hinge_bending"; }
    /// The serial pass (inside the training losses' batch loop) vectorised across hinges
    /// (energy/element_lanes.hpp, θ by lane_atan2); the parallel pass is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;
    bool has_column_pass() const override { return true; }
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const override;

    /// k_b = E t³ / (24 (1−ν²)) (N·m).
    double bending_stiffness() const { return m_bending_stiffness; }
    /// Rest dihedral angle θ̄ of hinge h (rad).
    double rest_angle(Index h) const { return m_rest_angles[size_t(h)]; }
    /// w_h = 3 k_b |ē|² / (Ā₁ + Ā₂).
    double hinge_weight(Index h) const { return m_weights[size_t(h)]; }

protected:
    double local_value(Index h, const ElementVector& xe) const override;
    ElementVector local_gradient(Index h, const ElementVector& xe) const override;
    double local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const override;
    ElementMatrix local_hessian(Index h, const ElementVector& xe) const override;

private:
    double m_bending_stiffness = 0.0;
    std::vector<double> m_rest_angles;
    std::vector<double> m_weights;
    ElementLanes<4, 2> m_lanes;  ///< the hinges with (w_h, θ̄), blocked for add_value_gradient
};

} // namespace lb
