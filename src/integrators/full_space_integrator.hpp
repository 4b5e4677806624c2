#pragma once
// The reference simulator behind the Integrator interface ("full_space" in the
// tables): every step is a full-space Newton solve; there is no latent.
#include "integrators/integrator.hpp"
#include "sim/full_space_simulator.hpp"

namespace lb {

class FullSpaceIntegrator final : public Integrator {
public:
    FullSpaceIntegrator(const PhysicsModel& model, NewtonOptions newton);

    std::string name() const override { return "full_space"; }
    void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
               const BoundaryState& bc_prev) override;
    /// The whole solve counts as integration; decoding is free (no latent).
    StepTiming step(const BoundaryState& bc) override;
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_empty; }
    const SolveSummary& last_summary() const { return m_summary; }

private:
    FullSpaceSimulator m_sim;
    VectorXd m_x, m_x_prev, m_x_prev2, m_empty;
    SolveSummary m_summary;
};

} // namespace lb
