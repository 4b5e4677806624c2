#include "energy/gravity_energy.hpp"

#include "energy/element_input.hpp"

namespace lb {

GravityEnergy::GravityEnergy(VectorXd masses, const Vector3d& gravity)
    : ElementEnergy<1>(detail::vertex_elements(masses.size())), m_masses(std::move(masses)), m_gravity(gravity)
{
    m_weights = (m_gravity * m_masses.transpose()).reshaped();
}

double GravityEnergy::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    g -= weight * m_weights;
    return -m_weights.dot(x);
}

double GravityEnergy::local_value(Index i, const ElementVector& xe) const
{
    return -m_masses[i] * m_gravity.dot(xe);
}

GravityEnergy::ElementVector GravityEnergy::local_gradient(Index i, const ElementVector&) const
{
    return -m_masses[i] * m_gravity;
}

GravityEnergy::ElementMatrix GravityEnergy::local_hessian(Index, const ElementVector&) const
{
    return ElementMatrix::Zero();
}

} // namespace lb
