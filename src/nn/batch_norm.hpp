#pragma once
// torch.nn.BatchNorm1d over features × batch data (statistics per feature row).
//
// Training mode (batch of B ≥ 2 samples):
//   μ = mean_b x,  σ² = mean_b (x − μ)²  (biased),  x̂ = (x − μ)/√(σ² + ε),  y = γ x̂ + β;
//   running_mean ← (1 − m) running_mean + m μ,
//   running_var  ← (1 − m) running_var  + m σ² B/(B − 1)   (unbiased, like PyTorch),
//   backward: dx = (1/√(σ² + ε)) (dx̂ − mean_b dx̂ − x̂ mean_b(dx̂ x̂)),  dx̂ = γ dy.
// Eval mode: y = γ (x − running_mean)/√(running_var + ε) + β, an affine map per feature.
#include "nn/layer.hpp"

namespace lb::nn {

class BatchNorm1d final : public Layer {
public:
    static constexpr double default_eps = 1e-5;
    static constexpr double default_momentum = 0.1;

    explicit BatchNorm1d(Index features, double eps = default_eps, double momentum = default_momentum);

    std::string type_name() const override { return "BatchNorm1d"; }
    Index in_features() const override { return m_weight.size(); }
    Index out_features() const override { return m_weight.size(); }

    BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) override;
    BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) override;
    /// Eval mode only (the per-feature affine map); throws std::logic_error after a
    /// training-mode forward.
    MatrixXd tangent(const MatrixXd& dX) const override;

    void collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out) override;
    void collect_buffers(const std::string& prefix, std::vector<BufferRef>& out) override;
    void describe(std::ostream& os) const override;
    std::unique_ptr<Layer> clone() const override { return std::make_unique<BatchNorm1d>(*this); }

    double eps() const { return m_eps; }
    double momentum() const { return m_momentum; }
    // Mutable access through Maps: assignment copies into the existing storage, so
    // ParameterRefs and optimisers stay attached (see Linear::weight).
    Eigen::Map<VectorXd> weight() { return {m_weight.data(), m_weight.size()}; }
    const VectorXd& weight() const { return m_weight; }
    Eigen::Map<VectorXd> bias() { return {m_bias.data(), m_bias.size()}; }
    const VectorXd& bias() const { return m_bias; }
    Eigen::Map<VectorXd> running_mean() { return {m_running_mean.data(), m_running_mean.size()}; }
    const VectorXd& running_mean() const { return m_running_mean; }
    Eigen::Map<VectorXd> running_var() { return {m_running_var.data(), m_running_var.size()}; }
    const VectorXd& running_var() const { return m_running_var; }
    long long num_batches_tracked() const { return static_cast<long long>(m_num_batches_tracked(0, 0)); }

    /// Eval-mode map y = scale ⊙ x + shift (used to fold BatchNorm into a Linear).
    VectorXd eval_scale() const;
    VectorXd eval_shift() const;

private:
    double m_eps, m_momentum;
    VectorXd m_weight, m_weight_grad, m_bias, m_bias_grad;
    VectorXd m_running_mean, m_running_var;
    MatrixXd m_num_batches_tracked;  ///< 1×1, an integer count kept as double for BufferRef

    // cache of the last forward
    bool m_training = false;
    MatrixXd m_x_hat;      ///< normalised input
    VectorXd m_inv_std;    ///< 1/√(σ² + ε) of the statistics used
    GrowingMatrix<double> m_output, m_input_grad;  ///< Y, dX
};

} // namespace lb::nn
