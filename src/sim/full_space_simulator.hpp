#pragma once
// Full-space implicit Euler: each step minimises the incremental potential
// over the free DOFs with Newton (NewtonSolver: the potential as a
// FreeDofObjective, Dirichlet DOFs removed and set to their prescribed values).
#include "sim/physics_model.hpp"
#include "solver/newton.hpp"

namespace lb {

class FullSpaceSimulator {
public:
    /// @param newton  tolerances; its force/length scales are overwritten from the model
    FullSpaceSimulator(const PhysicsModel& model, NewtonOptions newton);

    /// One step: x = argmin E(x; x_prev, x_prev2) with x_B = bc_targets (B×3).
    /// Warm start x̃ with boundary values set. x is resized and overwritten.
    SolveSummary step(const VectorXd& x_prev, const VectorXd& x_prev2, const MatrixX3d& bc_targets,
                      VectorXd& x);

    const PhysicsModel& model() const { return m_model; }
    const IncrementalPotential& potential() const { return m_potential; }
    const NewtonSolver& newton() const { return m_newton; }

private:
    const PhysicsModel& m_model;
    IncrementalPotential m_potential;
    NewtonSolver m_newton;
};

} // namespace lb
