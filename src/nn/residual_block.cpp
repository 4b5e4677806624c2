#include "nn/residual_block.hpp"

#include <stdexcept>
#include <utility>

#include "nn/batch_norm.hpp"

namespace lb::nn {

ResidualBlock::ResidualBlock(Index in_features, Index out_features, bool batch_norm, ActivationKind activation,
                             Rng& rng)
{
    m_f.emplace<Linear>(in_features, out_features, rng);
    if (batch_norm) m_f.emplace<BatchNorm1d>(out_features);
    m_f.emplace<Activation>(activation);
    m_f.emplace<Linear>(out_features, out_features, rng);
    if (batch_norm) m_f.emplace<BatchNorm1d>(out_features);
    if (in_features != out_features) m_skip.emplace(in_features, out_features, rng);
}

ResidualBlock::ResidualBlock(Sequential f, std::optional<Linear> skip) : m_f(std::move(f)), m_skip(std::move(skip))
{
    const Index in = m_f.in_features(), out = m_f.out_features();
    if (m_skip) {
        if (m_skip->in_features() != in || m_skip->out_features() != out)
            throw std::invalid_argument("ResidualBlock: projection shape does not match f");
    } else if (in != out) {
        throw std::invalid_argument("ResidualBlock: f maps " + std::to_string(in) + " -> " + std::to_string(out) +
                                    " features, an identity skip needs equal widths");
    }
}

BatchView ResidualBlock::forward(const Eigen::Ref<const MatrixXd>& X, bool training)
{
    auto Y = m_output.resize(out_features(), X.cols());
    Y = m_f.forward(X, training);
    if (m_skip)
        Y += m_skip->forward(X, training);
    else
        Y += X;
    return std::as_const(m_output).view();
}

BatchView ResidualBlock::backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate)
{
    auto dX = m_input_grad.resize(in_features(), dY.cols());
    dX = m_f.backward(dY, accumulate);
    if (m_skip)
        dX += m_skip->backward(dY, accumulate);
    else
        dX += dY;
    return std::as_const(m_input_grad).view();
}

MatrixXd ResidualBlock::tangent(const MatrixXd& dX) const
{
    MatrixXd dY = m_f.tangent(dX);
    if (m_skip)
        dY += m_skip->tangent(dX);
    else
        dY += dX;
    return dY;
}

void ResidualBlock::collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out)
{
    m_f.collect_parameters(prefix + "f.", out);
    if (m_skip) m_skip->collect_parameters(prefix + "skip.", out);
}

void ResidualBlock::collect_buffers(const std::string& prefix, std::vector<BufferRef>& out)
{
    m_f.collect_buffers(prefix + "f.", out);
}

void ResidualBlock::describe(std::ostream& os) const
{
    os << "{\"type\": \"ResidualBlock\", \"f\": ";
    m_f.describe(os);
    os << ", \"skip\": ";
    if (m_skip)
        m_skip->describe(os);
    else
        os << "null";
    os << "}";
}

} // namespace lb::nn

