#include "sim/full_space_simulator.hpp"

namespace lb {
namespace {
NewtonOptions scaled(NewtonOptions options, const PhysicsModel& model)
{
    options.force_scale = model.force_scale();
    options.length_scale = model.length_scale();
    return options;
}
} // namespace

FullSpaceSimulator::FullSpaceSimulator(const PhysicsModel& model, NewtonOptions newton)
    : m_model(model), m_potential(model, 0.0),
      m_newton(model.dof_to_unknown(), m_potential.terms(), scaled(newton, model))
{
}

SolveSummary FullSpaceSimulator::step(const VectorXd& x_prev, const VectorXd& x_prev2,
                                      const MatrixX3d& bc_targets, VectorXd& x)
{
    m_potential.set_previous(x_prev, x_prev2);
    x = m_potential.x_tilde();
    m_model.apply_bc(bc_targets, x);
    return m_newton.minimize(m_potential.terms(), x);
}

} // namespace lb
