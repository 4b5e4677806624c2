#include "energy/shell_membrane.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {

ShellMembrane::ShellMembrane(const Eigen::Ref<const MatrixX3d>& rest,
                             const Eigen::Ref<const MatrixXi>& triangles, double youngs,
                             double poisson, double thickness)
    : ElementEnergy(detail::checked_elements<3>(triangles, rest.rows(), "ShellMembrane"))
{
    detail::require_positive(youngs, "ShellMembrane", "Young's modulus");
    detail::require_poisson(poisson, "ShellMembrane");
    detail::require_positive(thickness, "ShellMembrane", "thickness");
    const LameParameters ps = plane_stress_lame_parameters(youngs, poisson);
    m_lame = {ps.mu * thickness, ps.lambda * thickness};

    const Index n = num_elements();
    m_shape_gradients.resize(size_t(n));
    m_areas.resize(size_t(n));
    for (Index f = 0; f < n; ++f) {
        const Vector3d X0 = rest.row(elements()(f, 0)).transpose();
        const Vector3d e1 = rest.row(elements()(f, 1)).transpose() - X0;
        const Vector3d e2 = rest.row(elements()(f, 2)).transpose() - X0;
        const Vector3d normal = e1.cross(e2);
        const double area = 0.5 * normal.norm();
        if (!(area > 0.0)) {
            std::ostringstream msg;
            msg << "ShellMembrane: triangle " << f << " is degenerate at rest (zero area)";
            throw Error(msg.str());
        }
        // Orthonormal rest frame (t1, t2) in the triangle's plane; Dm = rest edges in it.
        const Vector3d t1 = e1.normalized();
        const Vector3d t2 = normal.normalized().cross(t1);
        Eigen::Matrix2d Dm;
        Dm << e1.dot(t1), e2.dot(t1), e1.dot(t2), e2.dot(t2);
        const Eigen::Matrix2d Dm_inv = Dm.inverse();
        ShapeGradients& B = m_shape_gradients[size_t(f)];
        B.bottomRows<2>() = Dm_inv;
        B.row(0) = -Dm_inv.colwise().sum();
        m_areas[size_t(f)] = area;
    }
    m_lanes = StvkLanes<3, 2>(elements().data(), m_shape_gradients, m_areas, m_lame);
}

Eigen::Matrix<double, 3, 2> ShellMembrane::deformation_gradient(Index f, const ElementVector& xe) const
{
    return linear_deformation_gradient<3, 2>(xe, m_shape_gradients[size_t(f)]);
}

double ShellMembrane::local_value(Index f, const ElementVector& xe) const
{
    return m_areas[size_t(f)] * stvk_psi<2>(deformation_gradient(f, xe), m_lame);
}

ShellMembrane::ElementVector ShellMembrane::local_gradient(Index f, const ElementVector& xe) const
{
    return stvk_element_gradient<3, 2>(deformation_gradient(f, xe), m_shape_gradients[size_t(f)],
                                       m_areas[size_t(f)], m_lame);
}

double ShellMembrane::local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const
{
    return StvkLanes<3, 2>::evaluate(xe, m_shape_gradients[size_t(e)], m_areas[size_t(e)], m_lame, g);
}

ShellMembrane::ElementMatrix ShellMembrane::local_hessian(Index f, const ElementVector& xe) const
{
    // H = A Vec(∂F/∂x)ᵀ (∂P/∂F) Vec(∂F/∂x) with the 3×2 F of the rest frame; the blockwise
    // chain rule is derived above stvk_element_hessian (energy/stvk_density.hpp).
    return stvk_element_hessian<3, 2>(deformation_gradient(f, xe), m_shape_gradients[size_t(f)],
                                      m_areas[size_t(f)], m_lame);
}

double ShellMembrane::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    if (!serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
    return m_lanes.add_value_gradient(x, weight, g);
}

void ShellMembrane::add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
{
    m_lanes.add_value_gradient_columns(X, weight, G, values);
}

} // namespace lb
