#include "energy/rod_stretching.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {
namespace {
/// E = ½ k_s (|e| − |ē|)²/|ē| of one edge (p = {k_s, |ē|}) and its gradient
/// ∂E/∂x1 = k_s (|e| − |ē|)/|ē| · ê = −∂E/∂x0, one edge length for both. One SIMD lane of the
/// training pass, or one element (local_value_gradient).
const auto kStretchingKernel = [](const double (&x)[2][3], const auto& p, double (&g)[2][3]) {
    const double k = p[0], rest = p[1];
    const double e[3] = {x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]};
    const double length = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
    const double stretch = length - rest;
    const double s = k * stretch / (rest * length);
    for (int i = 0; i < 3; ++i) {
        g[1][i] = s * e[i];
        g[0][i] = -g[1][i];
    }
    return 0.5 * k * stretch * stretch / rest;
};

} // namespace

RodStretching::RodStretching(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& edges,
                             double youngs, double radius)
    : ElementEnergy(detail::checked_elements<2>(edges, rest.rows(), "RodStretching"))
{
    detail::require_positive(youngs, "RodStretching", "Young's modulus");
    detail::require_positive(radius, "RodStretching", "radius");
    m_stiffness = youngs * M_PI * radius * radius;
    m_rest_lengths.resize(size_t(num_elements()));
    for (Index e = 0; e < num_elements(); ++e) {
        const double length = (rest.row(elements()(e, 1)) - rest.row(elements()(e, 0))).norm();
        if (!(length > 0.0)) {
            std::ostringstream msg;
            msg << "RodStretching: edge " << e << " has zero rest length";
            throw Error(msg.str());
        }
        m_rest_lengths[size_t(e)] = length;
    }
    m_lanes = ElementLanes<2, 2>(num_elements(), elements().data(),
                                 [&](Index e) { return ElementLanes<2, 2>::Params{m_stiffness, m_rest_lengths[size_t(e)]}; });
}

double RodStretching::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    if (!serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
    return m_lanes.add_value_gradient(x, weight, g, kStretchingKernel);
}

void RodStretching::add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
{
    m_lanes.add_value_gradient_columns(X, weight, G, values, kStretchingKernel);
}

double RodStretching::local_value(Index e, const ElementVector& xe) const
{
    const double rest = m_rest_lengths[size_t(e)];
    const double stretch = (xe.segment<3>(3) - xe.segment<3>(0)).norm() - rest;
    return 0.5 * m_stiffness * stretch * stretch / rest;
}

RodStretching::ElementVector RodStretching::local_gradient(Index e, const ElementVector& xe) const
{
    ElementVector g;
    RodStretching::local_value_gradient(e, xe, g);
    return g;
}

double RodStretching::local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const
{
    return ElementLanes<2, 2>::evaluate(xe, {m_stiffness, m_rest_lengths[size_t(e)]}, g, kStretchingKernel);
}

RodStretching::ElementMatrix RodStretching::local_hessian(Index e, const ElementVector& xe) const
{
    // With e = x1 − x0, E = ½ k_s (|e| − |ē|)²/|ē|:
    //   ∂E/∂e = k_s (|e| − |ē|)/|ē| ê,  ∂ê/∂e = (I − êêᵀ)/|e|, so
    //   A = ∂²E/∂e² = k_s/|ē| [ êêᵀ + (|e| − |ē|)/|e| (I − êêᵀ) ],
    // and since ∂e/∂(x0, x1) = (−I, I): H = [[A, −A], [−A, A]]. A is indefinite in
    // compression (|e| < |ē|), which the PSD projection handles.
    const double rest = m_rest_lengths[size_t(e)];
    const Vector3d edge = xe.segment<3>(3) - xe.segment<3>(0);
    const double length = edge.norm();
    const Vector3d t = edge / length;
    const Matrix3d ttT = t * t.transpose();
    const Matrix3d A =
        m_stiffness / rest * (ttT + (length - rest) / length * (Matrix3d::Identity() - ttT));
    ElementMatrix H;
    H << A, -A, -A, A;
    return H;
}

} // namespace lb
