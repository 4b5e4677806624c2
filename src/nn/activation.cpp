#include "nn/activation.hpp"

#include <cassert>
#include <utility>

#include "core/error.hpp"

namespace lb::nn {

std::string to_string(ActivationKind kind)
{
    switch (kind) {
    case ActivationKind::identity: return "Identity";
    case ActivationKind::swish: return "Swish";
    case ActivationKind::tanh: return "Tanh";
    case ActivationKind::relu: return "ReLU";
    }
    return "?";
}

ActivationKind activation_from_string(const std::string& name)
{
    if (name == "Swish" || name == "swish" || name == "SiLU" || name == "silu") return ActivationKind::swish;
    if (name == "Tanh" || name == "tanh") return ActivationKind::tanh;
    if (name == "ReLU" || name == "relu") return ActivationKind::relu;
    if (name == "Identity" || name == "identity" || name == "none") return ActivationKind::identity;
    throw ConfigError("unknown activation '" + name + "' (expected swish, tanh, relu or identity)");
}

BatchView Activation::forward(const Eigen::Ref<const MatrixXd>& X, bool /*training*/)
{
    m_input.resize(X.rows(), X.cols()) = X;
    auto Y = m_output.resize(X.rows(), X.cols());
    Y = X;
    auto a = Y.array();
    apply_activation(m_kind, a);
    return std::as_const(m_output).view();
}

void Activation::scale_by_derivative(const Eigen::Ref<const MatrixXd>& dX, Eigen::Ref<MatrixXd> out) const
{
    assert(dX.rows() == m_input.rows() && out.rows() == dX.rows() && out.cols() == dX.cols());
    const auto d = m_input.view().unaryExpr([k = m_kind](double x) { return activation_derivative(k, x); });
    if (dX.cols() == m_input.cols()) {
        out = dX.cwiseProduct(d);
    } else {
        assert(m_input.cols() == 1);
        out = (dX.array().colwise() * d.col(0).array()).matrix();
    }
}

// The Jacobian is diagonal, so reverse and forward mode coincide.
BatchView Activation::backward(const Eigen::Ref<const MatrixXd>& dY, bool /*accumulate_parameter_gradients*/)
{
    scale_by_derivative(dY, m_input_grad.resize(dY.rows(), dY.cols()));
    return std::as_const(m_input_grad).view();
}

MatrixXd Activation::tangent(const MatrixXd& dX) const
{
    MatrixXd dY(dX.rows(), dX.cols());
    scale_by_derivative(dX, dY);
    return dY;
}

void Activation::describe(std::ostream& os) const { os << "{\"type\": \"" << type_name() << "\"}"; }

} // namespace lb::nn
