#pragma once
// Quadratic penalty pulling boundary vertices to prescribed positions, used in the
// learning losses of cloth and solids (DESIGN §3: w_bc = 1e5).
//
//   element   E_b = w |x_i − x*_b|²   (one boundary vertex i = indices[b] per element)
//   mesh      E = w Σ_{b∈B} |x_{i_b} − x*_b|²;  gradient 2w (x_i − x*_b);  Hessian 2w I
#include <vector>

#include "energy/energy.hpp"

namespace lb {

class DirichletPenalty final : public ElementEnergy<1> {
public:
    /// The penalty weight of DESIGN §3 (J/m²).
    static constexpr double kDefaultWeight = 1e5;

    /// @param indices  B boundary vertex indices (distinct, non-negative)
    /// @param weight   penalty weight w (J/m²)
    /// Targets start at zero: call set_targets before evaluating.
    DirichletPenalty(std::vector<int> indices, double weight = kDefaultWeight);

    std::string name() const override { return "dirichlet_penalty"; }
    /// One loop over the boundary vertices (no per-vertex call): the training losses
    /// evaluate it once per sample.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;

    /// @param targets  B×3 prescribed positions x*, row b for indices[b]
    void set_targets(const Eigen::Ref<const MatrixX3d>& targets);
    const MatrixX3d& targets() const { return m_targets; }
    const std::vector<int>& indices() const { return m_indices; }
    double weight() const { return m_weight; }

protected:
    double local_value(Index b, const ElementVector& xe) const override;
    ElementVector local_gradient(Index b, const ElementVector& xe) const override;
    ElementMatrix local_hessian(Index b, const ElementVector& xe) const override;

private:
    std::vector<int> m_indices;
    double m_weight;
    MatrixX3d m_targets;
};

} // namespace lb
