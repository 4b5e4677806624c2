#pragma once
// Rod stretching (Bergou et al. 2008), per edge of a rod network.
//
//   density   ½ k_s (ε)²,  ε = |e|/|ē| − 1 the axial strain, k_s = E·πr² (N)
//   element   E_e = ½ k_s (|e|/|ē| − 1)² |ē| = ½ k_s (|e| − |ē|)² / |ē|,  e = x1 − x0
//   mesh      E = Σ_e E_e
#include <vector>

#include "energy/element_lanes.hpp"
#include "energy/energy.hpp"

namespace lb {

class RodStretching final : public ElementEnergy<2> {
public:
    /// @param rest    N×3 rest positions (m)
    /// @param edges   E×2 vertex indices (non-zero rest length)
    /// @param youngs  Young's modulus E (Pa)
    /// @param radius  rod radius r (m)
    RodStretching(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& edges,
                  double youngs, double radius);

    std::string name() const override { return "rod_stretching"; }
    /// The serial pass (inside the training losses' batch loop) vectorised across elements
    /// (energy/element_lanes.hpp); the parallel pass is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;
    bool has_column_pass() const override { return true; }
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const override;

    /// k_s = E·πr² (N).
    double stretching_stiffness() const { return m_stiffness; }
    /// Rest length |ē| of edge e (m).
    double rest_length(Index e) const { return m_rest_lengths[size_t(e)]; }

protected:
    double local_value(Index e, const ElementVector& xe) const override;
    ElementVector local_gradient(Index e, const ElementVector& xe) const override;
    double local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const override;
    ElementMatrix local_hessian(Index e, const ElementVector& xe) const override;

private:
    double m_stiffness = 0.0;
    std::vector<double> m_rest_lengths;
    ElementLanes<2, 2> m_lanes;  ///< the edges with (k_s, |ē|), blocked for add_value_gradient
};

} // namespace lb
