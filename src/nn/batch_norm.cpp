#include "nn/batch_norm.hpp"

#include <cassert>
#include <stdexcept>
#include <utility>

namespace lb::nn {

BatchNorm1d::BatchNorm1d(Index features, double eps, double momentum)
    : m_eps(eps),
      m_momentum(momentum),
      m_weight(VectorXd::Ones(features)),
      m_weight_grad(VectorXd::Zero(features)),
      m_bias(VectorXd::Zero(features)),
      m_bias_grad(VectorXd::Zero(features)),
      m_running_mean(VectorXd::Zero(features)),
      m_running_var(VectorXd::Ones(features)),
      m_num_batches_tracked(MatrixXd::Zero(1, 1))
{
}

VectorXd BatchNorm1d::eval_scale() const
{
    return m_weight.array() / (m_running_var.array() + m_eps).sqrt();
}

VectorXd BatchNorm1d::eval_shift() const
{
    return m_bias.array() - eval_scale().array() * m_running_mean.array();
}

BatchView BatchNorm1d::forward(const Eigen::Ref<const MatrixXd>& X, bool training)
{
    assert(X.rows() == in_features());
    m_training = training;
    const Index B = X.cols();
    if (training) {
        if (B < 2)
            throw std::invalid_argument("BatchNorm1d: training mode needs more than 1 sample per batch");
        const VectorXd mean = X.rowwise().mean();
        const MatrixXd centered = X.colwise() - mean;
        const VectorXd var = centered.array().square().rowwise().mean();  // biased
        m_inv_std = (var.array() + m_eps).rsqrt();
        m_x_hat = centered.array().colwise() * m_inv_std.array();
        const double B_d = static_cast<double>(B);
        m_running_mean = (1.0 - m_momentum) * m_running_mean + m_momentum * mean;
        m_running_var = (1.0 - m_momentum) * m_running_var + m_momentum * var * (B_d / (B_d - 1.0));
        m_num_batches_tracked(0, 0) += 1.0;
    } else {
        m_inv_std = (m_running_var.array() + m_eps).rsqrt();
        m_x_hat = (X.colwise() - m_running_mean).array().colwise() * m_inv_std.array();
    }
    auto Y = m_output.resize(X.rows(), B);
    Y = (m_x_hat.array().colwise() * m_weight.array()).matrix();
    Y.colwise() += m_bias;
    return std::as_const(m_output).view();
}

BatchView BatchNorm1d::backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients)
{
    assert(dY.rows() == m_x_hat.rows());
    assert(dY.cols() == m_x_hat.cols() || (!accumulate_parameter_gradients && !m_training));
    if (accumulate_parameter_gradients) {
        m_weight_grad += dY.cwiseProduct(m_x_hat).rowwise().sum();
        m_bias_grad += dY.rowwise().sum();
    }
    const Eigen::ArrayXXd dx_hat = dY.array().colwise() * m_weight.array();
    auto dX_out = m_input_grad.resize(dY.rows(), dY.cols());
    if (!m_training) {
        dX_out = (dx_hat.colwise() * m_inv_std.array()).matrix();
        return std::as_const(m_input_grad).view();
    }
    // Through the batch statistics as well.
    const Eigen::ArrayXd mean_dx_hat = dx_hat.rowwise().mean();
    const Eigen::ArrayXd mean_dx_hat_x_hat = (dx_hat * m_x_hat.array()).rowwise().mean();
    const Eigen::ArrayXXd dX = (dx_hat.colwise() - mean_dx_hat) - m_x_hat.array().colwise() * mean_dx_hat_x_hat;
    dX_out = (dX.colwise() * m_inv_std.array()).matrix();
    return std::as_const(m_input_grad).view();
}

MatrixXd BatchNorm1d::tangent(const MatrixXd& dX) const
{
    if (m_training)
        throw std::logic_error("BatchNorm1d::tangent is defined for eval mode only (forward with training=false)");
    assert(dX.rows() == in_features());
    return (dX.array().colwise() * (m_weight.array() * m_inv_std.array())).matrix();
}

void BatchNorm1d::collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out)
{
    out.push_back({prefix + "weight", Eigen::Map<MatrixXd>(m_weight.data(), m_weight.size(), 1),
                   Eigen::Map<MatrixXd>(m_weight_grad.data(), m_weight_grad.size(), 1), true});
    out.push_back({prefix + "bias", Eigen::Map<MatrixXd>(m_bias.data(), m_bias.size(), 1),
                   Eigen::Map<MatrixXd>(m_bias_grad.data(), m_bias_grad.size(), 1), true});
}

void BatchNorm1d::collect_buffers(const std::string& prefix, std::vector<BufferRef>& out)
{
    out.push_back({prefix + "running_mean", Eigen::Map<MatrixXd>(m_running_mean.data(), m_running_mean.size(), 1), false});
    out.push_back({prefix + "running_var", Eigen::Map<MatrixXd>(m_running_var.data(), m_running_var.size(), 1), false});
    out.push_back({prefix + "num_batches_tracked", Eigen::Map<MatrixXd>(m_num_batches_tracked.data(), 1, 1), true});
}

void BatchNorm1d::describe(std::ostream& os) const
{
    os << "{\"type\": \"BatchNorm1d\", \"features\": " << in_features() << ", \"eps\": " << m_eps
       << ", \"momentum\": " << m_momentum << "}";
}

} // namespace lb::nn
