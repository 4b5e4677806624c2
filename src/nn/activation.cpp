#include "nn/activation.hpp"

#include <cassert>

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

MatrixXd Activation::forward(const MatrixXd& X, bool /*training*/)
{
    m_input = X;
    MatrixXd Y = X;
    auto a = Y.array();
    apply_activation(m_kind, a);
    return Y;
}

MatrixXd Activation::derivative() const
{
    return m_input.unaryExpr([k = m_kind](double x) { return activation_derivative(k, x); });
}

MatrixXd Activation::backward(const MatrixXd& dY, bool /*accumulate_parameter_gradients*/)
{
    return tangent(dY);  // the Jacobian is diagonal, so reverse and forward mode coincide
}

MatrixXd Activation::tangent(const MatrixXd& dX) const
{
    assert(dX.rows() == m_input.rows());
    const MatrixXd d = derivative();
    if (dX.cols() == d.cols()) return dX.cwiseProduct(d);
    assert(d.cols() == 1);
    return (dX.array().colwise() * d.col(0).array()).matrix();
}

void Activation::describe(std::ostream& os) const { os << "{\"type\": \"" << type_name() << "\"}"; }

} // namespace lb::nn
