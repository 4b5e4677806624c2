#include "energy/rod_bending.hpp"

#include <cmath>
#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"
#include "energy/rod_curvature.hpp"

namespace lb {
namespace {
// ∂(e0, e1)/∂(x0, x1, x2) for e0 = x1 − x0, e1 = x2 − x1 (6×9).
Eigen::Matrix<double, 6, 9> edge_map()
{
    Eigen::Matrix<double, 6, 9> S = Eigen::Matrix<double, 6, 9>::Zero();
    const Matrix3d I = Matrix3d::Identity();
    S.block<3, 3>(0, 0) = -I;
    S.block<3, 3>(0, 3) = I;
    S.block<3, 3>(3, 3) = -I;
    S.block<3, 3>(3, 6) = I;
    return S;
}

/// E = c |κb|² of one stencil (p = {c}) and its gradient: ∇_z E = 2c Jᵀκb over z = (e0, e1)
/// (curvature_binormal_vjp, J never formed), ∇_x E = Sᵀ ∇_z E. One SIMD lane of the training
/// pass, or one element (local_value_gradient).
const auto kBendingKernel = [](const double (&x)[3][3], const auto& p, double (&g)[3][3]) {
    double e0[3], e1[3], kb[3], gz[6];
    for (int i = 0; i < 3; ++i) {
        e0[i] = x[1][i] - x[0][i];
        e1[i] = x[2][i] - x[1][i];
    }
    const double kk = curvature_binormal_vjp(e0, e1, 2.0 * p[0], kb, gz);
    for (int i = 0; i < 3; ++i) {
        g[0][i] = -gz[i];
        g[1][i] = gz[i] - gz[3 + i];
        g[2][i] = gz[3 + i];
    }
    return p[0] * kk;
};

} // namespace

RodBending::RodBending(const Eigen::Ref<const MatrixX3d>& rest, const Eigen::Ref<const MatrixXi>& stencils,
                       double youngs, double radius)
    : ElementEnergy(detail::checked_elements<3>(stencils, rest.rows(), "RodBending"))
{
    detail::require_positive(youngs, "RodBending", "Young's modulus");
    detail::require_positive(radius, "RodBending", "radius");
    m_stiffness = youngs * M_PI * std::pow(radius, 4) / 4.0;
    m_rest_lengths.resize(size_t(num_elements()));
    for (Index i = 0; i < num_elements(); ++i) {
        const Vector3d e0 = (rest.row(elements()(i, 1)) - rest.row(elements()(i, 0))).transpose();
        const Vector3d e1 = (rest.row(elements()(i, 2)) - rest.row(elements()(i, 1))).transpose();
        if (!(e0.norm() > 0.0 && e1.norm() > 0.0)) {
            std::ostringstream msg;
            msg << "RodBending: stencil " << i << " has a zero-length rest edge";
            throw Error(msg.str());
        }
        const double kb = curvature_binormal(e0, e1).norm();
        if (!(kb <= kStraightTolerance)) {
            std::ostringstream msg;
            msg << "RodBending: stencil " << i << " (vertices " << elements()(i, 0) << ", "
                << elements()(i, 1) << ", " << elements()(i, 2) << ") is not straight at rest (|kb| = "
                << kb << "); the bending model assumes straight rest rods";
            throw Error(msg.str());
        }
        m_rest_lengths[size_t(i)] = e0.norm() + e1.norm();
    }
    m_lanes = ElementLanes<3, 1>(num_elements(), elements().data(),
                                 [&](Index i) { return ElementLanes<3, 1>::Params{m_stiffness / m_rest_lengths[size_t(i)]}; });
}

double RodBending::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    if (!serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
    return m_lanes.add_value_gradient(x, weight, g, kBendingKernel);
}

void RodBending::add_value_gradient_columns(const double* X, double weight, double* G, double* values) const
{
    m_lanes.add_value_gradient_columns(X, weight, G, values, kBendingKernel);
}

double RodBending::local_value(Index i, const ElementVector& xe) const
{
    const Vector3d kb =
        curvature_binormal(xe.segment<3>(3) - xe.segment<3>(0), xe.segment<3>(6) - xe.segment<3>(3));
    return m_stiffness / m_rest_lengths[size_t(i)] * kb.squaredNorm();
}

RodBending::ElementVector RodBending::local_gradient(Index i, const ElementVector& xe) const
{
    ElementVector g;
    RodBending::local_value_gradient(i, xe, g);
    return g;
}

double RodBending::local_value_gradient(Index i, const ElementVector& xe, ElementVector& g) const
{
    return ElementLanes<3, 1>::evaluate(xe, {m_stiffness / m_rest_lengths[size_t(i)]}, g, kBendingKernel);
}

RodBending::ElementMatrix RodBending::local_hessian(Index i, const ElementVector& xe) const
{
    // E = c κbᵀκb over z = (e0, e1) = S x (S linear, see edge_map):
    //   ∇²_z E = 2c (JᵀJ + Σ_k κb_k ∇²_z κb_k),
    // the second term being the contracted Hessian of κb with the weights w = κb held
    // fixed (rod_curvature.cpp derives it). Then ∇²_x E = Sᵀ ∇²_z E S.
    const Vector3d e0 = xe.segment<3>(3) - xe.segment<3>(0);
    const Vector3d e1 = xe.segment<3>(6) - xe.segment<3>(3);
    Matrix36d J;
    const Vector3d kb = curvature_binormal(e0, e1, &J);
    const double c = m_stiffness / m_rest_lengths[size_t(i)];
    const Matrix6d Hz = 2.0 * c * (J.transpose() * J + curvature_binormal_contracted_hessian(e0, e1, kb));
    static const Eigen::Matrix<double, 6, 9> S = edge_map();
    return S.transpose() * Hz * S;
}

} // namespace lb
