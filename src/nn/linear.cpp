#include "nn/linear.hpp"

#include <cassert>
#include <utility>

#include "nn/init.hpp"
#include "nn/small_product.hpp"

namespace lb::nn {

Linear::Linear(Index in_features, Index out_features)
    : m_weight(MatrixXd::Zero(out_features, in_features)),
      m_weight_grad(MatrixXd::Zero(out_features, in_features)),
      m_bias(VectorXd::Zero(out_features)),
      m_bias_grad(VectorXd::Zero(out_features))
{
}

Linear::Linear(Index in_features, Index out_features, Rng& rng) : Linear(in_features, out_features)
{
    init_linear_default(m_weight, m_bias, rng);
}

BatchView Linear::forward(const Eigen::Ref<const MatrixXd>& X, bool /*training*/)
{
    assert(X.rows() == in_features());
    m_input.resize(X.rows(), X.cols()) = X;
    auto Y = m_output.resize(out_features(), X.cols());
    gemm<double>(m_weight, false, X, Y, GemmOp::assign, m_gemm);
    Y.colwise() += m_bias;
    return std::as_const(m_output).view();
}

BatchView Linear::backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients)
{
    assert(dY.rows() == out_features());
    if (accumulate_parameter_gradients) {
        assert(dY.cols() == m_input.cols());
        gemm<double>(dY, false, m_input.view(), true, m_weight_grad, GemmOp::add, m_gemm);
        m_bias_grad += dY.rowwise().sum();
    }
    auto dX = m_input_grad.resize(in_features(), dY.cols());
    if (dY.cols() <= small_product_max_columns) {
        dX.setZero();
        add_transpose_product(m_weight, dY, dX);
    } else {
        gemm<double>(m_weight, true, dY, dX, GemmOp::assign, m_gemm);
    }
    return std::as_const(m_input_grad).view();
}

void Linear::collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out)
{
    out.push_back({prefix + "weight", Eigen::Map<MatrixXd>(m_weight.data(), m_weight.rows(), m_weight.cols()),
                   Eigen::Map<MatrixXd>(m_weight_grad.data(), m_weight_grad.rows(), m_weight_grad.cols())});
    out.push_back({prefix + "bias", Eigen::Map<MatrixXd>(m_bias.data(), m_bias.size(), 1),
                   Eigen::Map<MatrixXd>(m_bias_grad.data(), m_bias_grad.size(), 1), true});
}

void Linear::describe(std::ostream& os) const
{
    os << "{\"type\": \"Linear\", \"in\": " << in_features() << ", \"out\": " << out_features() << "}";
}

} // namespace lb::nn
