#include "energy/shell_hinge_bending.hpp"

#include <Eigen/Geometry>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {

ShellHingeBending::ShellHingeBending(const Eigen::Ref<const MatrixX3d>& rest,
                                     const Eigen::Ref<const MatrixXi>& hinges, double youngs,
                                     double poisson, double thickness)
    : InlinedElementEnergy(detail::checked_elements<4>(hinges, rest.rows(), "ShellHingeBending"))
{
    detail::require_positive(youngs, "ShellHingeBending", "Young's modulus");
    detail::require_poisson(poisson, "ShellHingeBending");
    detail::require_positive(thickness, "ShellHingeBending", "thickness");
    m_bending_stiffness = youngs * thickness * thickness * thickness / (24.0 * (1.0 - poisson * poisson));

    const VectorXd x_rest = flatten(rest);
    const Index n = num_elements();
    m_rest_angles.resize(size_t(n));
    m_weights.resize(size_t(n));
    for (Index h = 0; h < n; ++h) {
        const ElementVector xe = gather(h, x_rest);
        const Vector3d x0 = xe.segment<3>(0);
        const Vector3d e = xe.segment<3>(3) - x0;
        const double area1 = 0.5 * e.cross(xe.segment<3>(6) - x0).norm();
        const double area2 = 0.5 * (xe.segment<3>(9) - x0).cross(e).norm();
        if (!(area1 > 0.0 && area2 > 0.0)) {
            std::ostringstream msg;
            msg << "ShellHingeBending: hinge " << h << " has a degenerate rest triangle";
            throw Error(msg.str());
        }
        m_rest_angles[size_t(h)] = dihedral_angle(xe);
        m_weights[size_t(h)] = 3.0 * m_bending_stiffness * e.squaredNorm() / (area1 + area2);
    }
}

double ShellHingeBending::local_value(Index h, const ElementVector& xe) const
{
    const double delta = wrap_angle(dihedral_angle(xe) - m_rest_angles[size_t(h)]);
    return m_weights[size_t(h)] * delta * delta;
}

ShellHingeBending::ElementVector ShellHingeBending::local_gradient(Index h, const ElementVector& xe) const
{
    ElementVector g_theta;
    const double theta = dihedral_angle(xe, &g_theta, nullptr);
    const double delta = wrap_angle(theta - m_rest_angles[size_t(h)]);
    return 2.0 * m_weights[size_t(h)] * delta * g_theta;
}

double ShellHingeBending::local_value_gradient(Index h, const ElementVector& xe, ElementVector& g) const
{
    ElementVector g_theta;
    const double theta = dihedral_angle(xe, &g_theta, nullptr);
    const double delta = wrap_angle(theta - m_rest_angles[size_t(h)]);
    g = 2.0 * m_weights[size_t(h)] * delta * g_theta;
    return m_weights[size_t(h)] * delta * delta;
}

ShellHingeBending::ElementMatrix ShellHingeBending::local_hessian(Index h, const ElementVector& xe) const
{
    // E = w (θ − θ̄)²  ⇒  ∇²E = 2w (∇θ ∇θᵀ + (θ − θ̄) ∇²θ), with ∇θ, ∇²θ exact
    // (derivation in dihedral_angle.cpp).
    ElementVector g_theta;
    ElementMatrix H_theta;
    const double theta = dihedral_angle(xe, &g_theta, &H_theta);
    const double delta = wrap_angle(theta - m_rest_angles[size_t(h)]);
    const double w2 = 2.0 * m_weights[size_t(h)];
    return w2 * (g_theta * g_theta.transpose() + delta * H_theta);
}

} // namespace lb
