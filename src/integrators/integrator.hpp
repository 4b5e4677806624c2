#pragma once
// The interface every method implements — the paper's latent integrator and
// every baseline — so that rollouts, metrics and timing treat them alike.
//
// Protocol (DESIGN §6): reset() with the two starting frames (t−2, t−1), then
// step() once per frame with that frame's boundary state; after each step,
// positions() is the decoded full state x_t (3N) and latent() its latent code
// (empty for full-space methods). step() reports the time spent integrating
// (latent update) and decoding (latent → full positions) separately.
#include <string>

#include "core/types.hpp"

namespace lb {

/// The boundary at one frame: parameters p_t (P) and Dirichlet targets (3B, xyz interleaved).
struct BoundaryState {
    VectorXd params;
    VectorXd targets;
};

struct StepTiming {
    double integrate_seconds = 0.0;
    double decode_seconds = 0.0;
    double total() const { return integrate_seconds + decode_seconds; }
};

class Integrator {
public:
    virtual ~Integrator() = default;

    virtual std::string name() const = 0;
    /// Start from full states x_{t−2}, x_{t−1} (3N) and their boundary states.
    virtual void reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
                       const BoundaryState& bc_prev) = 0;
    /// Advance one frame under `bc` (the boundary of the new frame).
    virtual StepTiming step(const BoundaryState& bc) = 0;
    /// Decoded full state of the current frame (3N).
    virtual const VectorXd& positions() const = 0;
    /// Latent code of the current frame (empty for full-space methods).
    virtual const VectorXd& latent() const = 0;
};

} // namespace lb
