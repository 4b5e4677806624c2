#pragma once
// Residual MLP block (the "MLP-ResNet" unit of the autoencoder, paper §3.2):
//
//   y = skip(x) + f(x),   f = Linear(in→out) → BatchNorm → act → Linear(out→out) → BatchNorm,
//   skip = identity if in == out, else Linear(in→out) (a learned projection, with bias).
//
// Choice: no activation after the sum, so consecutive blocks keep a clean identity
// path (as in pre-activation ResNets); the second BatchNorm lets f start near a
// small perturbation of the skip. With batch_norm = false the BatchNorms are
// omitted. Parameters are named "f.<i>.<param>" and "skip.<param>".
#include <optional>

#include "core/rng.hpp"
#include "nn/activation.hpp"
#include "nn/linear.hpp"
#include "nn/sequential.hpp"

namespace lb::nn {

class ResidualBlock final : public Layer {
public:
    /// The standard block described above, PyTorch-default initialised.
    ResidualBlock(Index in_features, Index out_features, bool batch_norm, ActivationKind activation, Rng& rng);
    /// A block with an arbitrary inner network f and optional projection (for loading).
    ResidualBlock(Sequential f, std::optional<Linear> skip);

    std::string type_name() const override { return "ResidualBlock"; }
    Index in_features() const override { return m_f.in_features(); }
    Index out_features() const override { return m_f.out_features(); }

    BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) override;
    BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) override;
    MatrixXd tangent(const MatrixXd& dX) const override;

    void collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out) override;
    void collect_buffers(const std::string& prefix, std::vector<BufferRef>& out) override;
    /// {"type": "ResidualBlock", "f": {Sequential}, "skip": {Linear} | null}
    void describe(std::ostream& os) const override;
    std::unique_ptr<Layer> clone() const override { return std::make_unique<ResidualBlock>(*this); }

    Sequential& f() { return m_f; }
    const Sequential& f() const { return m_f; }
    bool has_projection() const { return m_skip.has_value(); }
    Linear& projection() { return *m_skip; }
    const Linear& projection() const { return *m_skip; }

private:
    Sequential m_f;
    std::optional<Linear> m_skip;
    GrowingMatrix<double> m_output, m_input_grad;  ///< Y, dX
};

} // namespace lb::nn
