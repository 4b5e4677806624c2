#pragma once
// Fully connected layer  Y = W X + b 1ᵀ  (torch.nn.Linear).
#include "core/rng.hpp"
#include "nn/layer.hpp"

namespace lb::nn {

class Linear final : public Layer {
public:
    /// PyTorch-default initialisation (see init.hpp) drawn from `rng`.
    Linear(Index in_features, Index out_features, Rng& rng);
    /// Zero-initialised (weights to be loaded or set).
    Linear(Index in_features, Index out_features);

    std::string type_name() const override { return "Linear"; }
    Index in_features() const override { return m_weight.cols(); }
    Index out_features() const override { return m_weight.rows(); }

    BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) override;
    /// dX = Wᵀ dY;  dW += dY Xᵀ;  db += dY 1.
    BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) override;
    MatrixXd tangent(const MatrixXd& dX) const override { return m_weight * dX; }

    void collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out) override;
    void describe(std::ostream& os) const override;
    std::unique_ptr<Layer> clone() const override { return std::make_unique<Linear>(*this); }

    /// out × in. Mutable access is a Map so that assigning to it copies into the
    /// existing storage (a move-assignment would silently detach ParameterRefs and
    /// optimisers); the shape is fixed at construction.
    Eigen::Map<MatrixXd> weight() { return {m_weight.data(), m_weight.rows(), m_weight.cols()}; }
    const MatrixXd& weight() const { return m_weight; }
    /// out
    Eigen::Map<VectorXd> bias() { return {m_bias.data(), m_bias.size()}; }
    const VectorXd& bias() const { return m_bias; }

private:
    MatrixXd m_weight, m_weight_grad;
    VectorXd m_bias, m_bias_grad;
    GrowingMatrix<double> m_input;                 ///< cached X
    GrowingMatrix<double> m_output, m_input_grad;  ///< Y, dX
    GemmWorkspace<double> m_gemm;
};

} // namespace lb::nn
