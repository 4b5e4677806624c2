#pragma once
// Adam (Kingma & Ba 2015) with PyTorch's defaults and update rule (torch.optim.Adam,
// L2 weight decay added to the gradient, not decoupled):
//   g ← grad + λ θ,  m ← β₁ m + (1−β₁) g,  v ← β₂ v + (1−β₂) g²,
//   θ ← θ − lr · (m / (1−β₁ᵗ)) / (√(v / (1−β₂ᵗ)) + ε).
#include <vector>

#include "nn/layer.hpp"

namespace lb::nn {

struct AdamOptions {
    double lr = 1e-3;
    double beta1 = 0.9;
    double beta2 = 0.999;
    double eps = 1e-8;
    double weight_decay = 0.0;
};

/// Everything an optimiser checkpoint needs to resume bit for bit.
struct AdamState {
    long long step = 0;
    std::vector<MatrixXd> m, v;  ///< first / second moments, one per parameter (parameter shapes)
};

class Adam {
public:
    /// The parameter references must stay valid (their network alive) while the
    /// optimiser is used.
    explicit Adam(std::vector<ParameterRef> parameters, AdamOptions options = {});

    /// One update from the gradients currently stored in the parameters.
    void step();
    /// Zero every parameter's gradient.
    void zero_grad();

    double learning_rate() const { return m_options.lr; }
    void set_learning_rate(double lr) { m_options.lr = lr; }
    long long steps() const { return m_state.step; }
    const AdamOptions& options() const { return m_options; }

    /// Step count and moments (for checkpoints).
    const AdamState& state() const { return m_state; }
    /// Restore a state taken from state(); throws std::invalid_argument if the number
    /// or shapes of the moments do not match the parameters.
    void set_state(AdamState state);

private:
    std::vector<ParameterRef> m_parameters;
    AdamOptions m_options;
    AdamState m_state;
};

} // namespace lb::nn
