#include "integrators/full_space_integrator.hpp"

#include <limits>

#include "core/error.hpp"
#include "core/timer.hpp"

namespace lb {

FullSpaceIntegrator::FullSpaceIntegrator(const PhysicsModel& model, NewtonOptions newton) : m_sim(model, newton) { }

void FullSpaceIntegrator::reset(const VectorXd& x_prev2, const BoundaryState&, const VectorXd& x_prev,
                                const BoundaryState&)
{
    m_x_prev2 = x_prev2;
    m_x_prev = x_prev;
    m_x = x_prev;
}

StepTiming FullSpaceIntegrator::step(const BoundaryState& bc)
{
    Timer timer;
    const MatrixX3d targets = Eigen::Map<const MatrixX3d>(bc.targets.data(), bc.targets.size() / 3, 3);
    m_summary = m_sim.step(m_x_prev, m_x_prev2, targets, m_x);
    if (m_summary.termination == SolveTermination::NonFinite) {
        // A non-finite state (e.g. started from one) ends the rollout like any method's.
        m_x.setConstant(std::numeric_limits<double>::quiet_NaN());
    } else if (!m_summary.converged()) {
        throw NumericalError("full-space step did not converge: " + m_summary.brief());
    }
    m_x_prev2.swap(m_x_prev);
    m_x_prev = m_x;
    return {timer.seconds(), 0.0};
}

} // namespace lb
