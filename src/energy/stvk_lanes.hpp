#pragma once
// Linear St. Venant–Kirchhoff elements (TetStVK: K = 4, D = 3; ShellMembrane: K = 3, D = 2)
// in the element-vectorised training pass (energy/element_lanes.hpp): the lane parameters
// (shape gradients and rest measure, stvk_lane_params) and the one value-and-gradient kernel
// (stvk_lane_value_gradient, energy/stvk_density.hpp) that both the blocked pass and the
// per-element local_value_gradient run.
#include <vector>

#include "energy/element_lanes.hpp"
#include "energy/stvk_density.hpp"

namespace lb {

template <int K, int D>
class StvkLanes {
public:
    using Lanes = ElementLanes<K, K * D + 1>;
    using ShapeGradients = Eigen::Matrix<double, K, D>;
    using ElementVector = Eigen::Matrix<double, 3 * K, 1>;

    StvkLanes() = default;
    /// @param nodes     K vertex indices of element e at nodes[K e + a]
    /// @param B         per element its shape gradients; @param measures per element V
    StvkLanes(const int* nodes, const std::vector<ShapeGradients>& B, const std::vector<double>& measures,
              const LameParameters& lame)
        : m_lanes(Index(B.size()), nodes, [&](Index e) { return stvk_lane_params<K, D>(B[size_t(e)], measures[size_t(e)]); }),
          m_lame(lame)
    {
    }

    /// Σ_e V_e ψ(F_e), adding weight · its gradient to g (the serial pass).
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
    {
        return m_lanes.add_value_gradient(x, weight, g, kernel(m_lame));
    }

    /// The same pass over Energy::kColumnLanes samples (Energy::add_value_gradient_columns).
    void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
    {
        m_lanes.add_value_gradient_columns(X, weight, G, values, kernel(m_lame));
    }

    /// One element (gathered xe, gradient g): local_value_gradient.
    static double evaluate(const ElementVector& xe, const ShapeGradients& B, double measure, const LameParameters& lame,
                           ElementVector& g)
    {
        return Lanes::evaluate(xe, stvk_lane_params<K, D>(B, measure), g, kernel(lame));
    }

private:
    static auto kernel(const LameParameters& lame)
    {
        return [lame](const auto& x, const auto& p, auto& g) { return stvk_lane_value_gradient<K, D>(x, p, lame, g); };
    }

    Lanes m_lanes;
    LameParameters m_lame;
};

} // namespace lb
