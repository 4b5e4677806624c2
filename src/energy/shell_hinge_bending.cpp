#include "energy/shell_hinge_bending.hpp"

#include <Eigen/Geometry>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {
namespace {

/// E_h = w_h (θ − θ̄)² of one hinge (p = {w_h, θ̄}) and its gradient 2 w_h (θ − θ̄) ∇θ, θ and ∇θ
/// by dihedral_angle_gradient. One SIMD lane of the training pass, or one element
/// (local_value_gradient).
const auto kHingeKernel = [](const double (&x)[4][3], const auto& p, double (&g)[4][3]) {
    const double w = p[0], rest_angle = p[1];
    double g_theta[4][3];
    // θ, θ̄ ∈ [−π, π]: wrap_angle_difference, not wrap_angle, whose fmod branch would keep
    // the lane loop scalar.
    const double delta = wrap_angle_difference(dihedral_angle_gradient(x, g_theta) - rest_angle);
    const double c = 2.0 * w * delta;
    for (int a = 0; a < 4; ++a) {
        for (int i = 0; i < 3; ++i) g[a][i] = c * g_theta[a][i];
    }
    return w * delta * delta;
};

} // namespace

ShellHingeBending::ShellHingeBending(const Eigen::Ref<const MatrixX3d>& rest,
                                     const Eigen::Ref<const MatrixXi>& hinges, double youngs,
                                     double poisson, double thickness)
    : ElementEnergy(detail::checked_elements<4>(hinges, rest.rows(), "ShellHingeBending"))
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
    m_lanes = ElementLanes<4, 2>(n, elements().data(), [&](Index h) {
        return ElementLanes<4, 2>::Params{m_weights[size_t(h)], m_rest_angles[size_t(h)]};
    });
}

double ShellHingeBending::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    if (!serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
    return m_lanes.add_value_gradient(x, weight, g, kHingeKernel);
}

void ShellHingeBending::add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
{
    m_lanes.add_value_gradient_columns(X, weight, G, values, kHingeKernel);
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
    return ElementLanes<4, 2>::evaluate(xe, {m_weights[size_t(h)], m_rest_angles[size_t(h)]}, g, kHingeKernel);
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
