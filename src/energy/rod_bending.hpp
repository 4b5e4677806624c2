#pragma once
// Rod bending (Bergou et al. 2008; isotropic, twist-free, straight at rest), per
// interior rod vertex with stencil (i−1, i, i+1).
//
//   density   E·I ||κb||² / l̄ per vertex, I = πr⁴/4 (second moment of area)
//   element   E_i = E·I ||κb_i||² / l̄_i,  l̄_i = |ē_{i−1}| + |ē_i|,
//             κb_i = 2 e_{i−1}×e_i / (|e_{i−1}||e_i| + e_{i−1}·e_i)  (energy/rod_curvature.hpp)
//   mesh      E = Σ_i E_i
//
// Rest curvature is zero (κb̄_i = 0, as the rods are straight at rest); a curved rest
// stencil is rejected, since a world-frame κb̄ would break rotation invariance.
// Check: an arc of radius R with n equal segments stores (n−1)/n · ½ E·I·L/R² to
// leading order (the end vertices carry no term): 0.990 for n = 100.
#include <vector>

#include "energy/element_lanes.hpp"
#include "energy/energy.hpp"

namespace lb {

class RodBending final : public ElementEnergy<3> {
public:
    /// Largest rest turning measure |κb̄| accepted as straight (dimensionless, 2 tan(φ̄/2)).
    static constexpr double kStraightTolerance = 1e-6;

    /// @param rest      N×3 rest positions (m)
    /// @param stencils  M×3 vertex indices (i−1, i, i+1) (mesh::rod_bending_stencils)
    /// @param youngs    Young's modulus E (Pa)
    /// @param radius    rod radius r (m)
    /// @throws Error on bad input or a stencil that is not straight at rest
    RodBending(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& stencils,
               double youngs, double radius);

    std::string name() const override { return "rod_bending"; }
    /// The serial pass (inside the training losses' batch loop) vectorised across elements
    /// (energy/element_lanes.hpp); the parallel pass is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;
    bool has_column_pass() const override { return true; }
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const override;

    /// E·I = E·πr⁴/4 (N·m²).
    double bending_stiffness() const { return m_stiffness; }
    /// l̄_i = |ē_{i−1}| + |ē_i| (m).
    double rest_length(Index i) const { return m_rest_lengths[size_t(i)]; }

protected:
    double local_value(Index i, const ElementVector& xe) const override;
    ElementVector local_gradient(Index i, const ElementVector& xe) const override;
    double local_value_gradient(Index i, const ElementVector& xe, ElementVector& g) const override;
    ElementMatrix local_hessian(Index i, const ElementVector& xe) const override;

private:
    double m_stiffness = 0.0;
    std::vector<double> m_rest_lengths;
    ElementLanes<3, 1> m_lanes;  ///< the stencils with c_i = E·I/l̄_i, blocked for add_value_gradient
};

} // namespace lb
