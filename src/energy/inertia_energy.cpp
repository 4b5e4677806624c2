#include "energy/inertia_energy.hpp"

#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {

InertiaEnergy::InertiaEnergy(VectorXd masses, double dt)
    : ElementEnergy<1>(detail::vertex_elements(masses.size())),
      m_masses(std::move(masses)),
      m_dt(dt),
      m_inv_dt2(1.0 / (dt * dt)),
      m_x_tilde(VectorXd::Zero(3 * m_masses.size()))
{
    detail::require_positive(dt, "InertiaEnergy", "time step dt");
    if (m_masses.size() > 0 && !(m_masses.minCoeff() >= 0.0)) {
        throw Error("InertiaEnergy: vertex masses must be non-negative");
    }
    m_dof_weights = (m_inv_dt2 * m_masses).replicate(1, 3).transpose().reshaped();
}

void InertiaEnergy::require_size(const char* caller, Index size) const
{
    if (size == m_x_tilde.size()) return;
    std::ostringstream msg;
    msg << "InertiaEnergy::" << caller << ": expected " << m_x_tilde.size() << " values (3N), got " << size;
    throw Error(msg.str());
}

void InertiaEnergy::set_x_tilde(const Eigen::Ref<const VectorXd>& x_tilde)
{
    require_size("set_x_tilde", x_tilde.size());
    m_x_tilde = x_tilde;
}

void InertiaEnergy::set_previous(const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2)
{
    require_size("set_previous", x_prev.size());
    require_size("set_previous", x_prev2.size());
    m_x_tilde.noalias() = inertial_target(x_prev, x_prev2);
}

double InertiaEnergy::local_value(Index i, const ElementVector& xe) const
{
    return 0.5 * m_inv_dt2 * m_masses[i] * (xe - m_x_tilde.segment<3>(3 * i)).squaredNorm();
}

InertiaEnergy::ElementVector InertiaEnergy::local_gradient(Index i, const ElementVector& xe) const
{
    return m_inv_dt2 * m_masses[i] * (xe - m_x_tilde.segment<3>(3 * i));
}

double InertiaEnergy::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    // ½ Σ_i m_i/h² |x_i − x̃_i|², gradient m_i/h² (x_i − x̃_i); no temporaries.
    const auto d = x.array() - m_x_tilde.array();
    g.array() += weight * m_dof_weights.array() * d;
    return 0.5 * (m_dof_weights.array() * d.square()).sum();
}

InertiaEnergy::ElementMatrix InertiaEnergy::local_hessian(Index i, const ElementVector&) const
{
    return m_inv_dt2 * m_masses[i] * ElementMatrix::Identity();
}

} // namespace lb
