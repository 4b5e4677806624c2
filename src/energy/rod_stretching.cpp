#include "energy/rod_stretching.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {

RodStretching::RodStretching(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& edges,
                             double youngs, double radius)
    : InlinedElementEnergy(detail::checked_elements<2>(edges, rest.rows(), "RodStretching"))
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
    // ∂E/∂x1 = k_s (|e| − |ē|)/|ē| · ê = −∂E/∂x0; one edge length for both.
    const double rest = m_rest_lengths[size_t(e)];
    const Vector3d edge = xe.segment<3>(3) - xe.segment<3>(0);
    const double length = edge.norm();
    const double stretch = length - rest;
    const Vector3d g1 = m_stiffness * stretch / (rest * length) * edge;
    g << -g1, g1;
    return 0.5 * m_stiffness * stretch * stretch / rest;
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
