#include "energy/tet_stvk.hpp"

#include <Eigen/LU>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {

TetStVK::TetStVK(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& tets,
                 double youngs, double poisson)
    : ElementEnergy(detail::checked_elements<4>(tets, rest.rows(), "TetStVK"))
{
    detail::require_positive(youngs, "TetStVK", "Young's modulus");
    detail::require_poisson(poisson, "TetStVK");
    m_lame = lame_parameters(youngs, poisson);

    const Index n = num_elements();
    m_shape_gradients.resize(size_t(n));
    m_volumes.resize(size_t(n));
    for (Index t = 0; t < n; ++t) {
        const Vector3d X0 = rest.row(elements()(t, 0)).transpose();
        Matrix3d Dm;
        for (int a = 1; a < 4; ++a) Dm.col(a - 1) = rest.row(elements()(t, a)).transpose() - X0;
        const double det = Dm.determinant();
        if (!(det > 0.0)) {
            std::ostringstream msg;
            msg << "TetStVK: tetrahedron " << t << " has non-positive rest volume (det Dm = " << det
                << "); tets must be positively oriented";
            throw Error(msg.str());
        }
        const Matrix3d Dm_inv = Dm.inverse();
        ShapeGradients& B = m_shape_gradients[size_t(t)];
        B.bottomRows<3>() = Dm_inv;
        B.row(0) = -Dm_inv.colwise().sum();
        m_volumes[size_t(t)] = det / 6.0;
    }
    m_lanes = StvkLanes<4, 3>(elements().data(), m_shape_gradients, m_volumes, m_lame);
}

Matrix3d TetStVK::deformation_gradient(Index t, const ElementVector& xe) const
{
    return linear_deformation_gradient<4, 3>(xe, m_shape_gradients[size_t(t)]);
}

double TetStVK::local_value(Index t, const ElementVector& xe) const
{
    return m_volumes[size_t(t)] * stvk_psi<3>(deformation_gradient(t, xe), m_lame);
}

TetStVK::ElementVector TetStVK::local_gradient(Index t, const ElementVector& xe) const
{
    return stvk_element_gradient<4, 3>(deformation_gradient(t, xe), m_shape_gradients[size_t(t)],
                                       m_volumes[size_t(t)], m_lame);
}

double TetStVK::local_value_gradient(Index t, const ElementVector& xe, ElementVector& g) const
{
    return StvkLanes<4, 3>::evaluate(xe, m_shape_gradients[size_t(t)], m_volumes[size_t(t)], m_lame, g);
}

TetStVK::ElementMatrix TetStVK::local_hessian(Index t, const ElementVector& xe) const
{
    // H = V Vec(∂F/∂x)ᵀ (∂P/∂F) Vec(∂F/∂x), formed blockwise: see stvk_element_hessian.
    return stvk_element_hessian<4, 3>(deformation_gradient(t, xe), m_shape_gradients[size_t(t)],
                                      m_volumes[size_t(t)], m_lame);
}

TetStVK::ElementMatrix TetStVK::local_projected_hessian(Index t, const ElementVector& xe) const
{
    // V Jᵀ (∂P/∂F)₊ J from the analytic eigensystem of ∂P/∂F: see stvk_element_projected_hessian.
    return stvk_element_projected_hessian<4>(deformation_gradient(t, xe), m_shape_gradients[size_t(t)],
                                             m_volumes[size_t(t)], m_lame);
}

double TetStVK::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    if (!serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
    return m_lanes.add_value_gradient(x, weight, g);
}

void TetStVK::add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
{
    m_lanes.add_value_gradient_columns(X, weight, G, values);
}

} // namespace lb
