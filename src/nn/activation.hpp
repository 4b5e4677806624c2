#pragma once
// Element-wise activations. Swish (= SiLU) is the one the paper uses:
//   swish(x) = x σ(x),   swish'(x) = σ(x) (1 + x (1 − σ(x))),   σ(x) = 1/(1 + e^{−x}).
// Tanh and ReLU exist for experiments (ReLU is not differentiable at 0; its
// derivative there is taken as 0, like PyTorch).
#include <cmath>
#include <string>

#include "nn/layer.hpp"

namespace lb::nn {

enum class ActivationKind { identity, swish, tanh, relu };

std::string to_string(ActivationKind kind);
/// Inverse of to_string; throws ConfigError naming the accepted values.
ActivationKind activation_from_string(const std::string& name);

/// Scalar value and derivative, templated for the float inference path.
template <typename T>
inline T activation_value(ActivationKind kind, T x)
{
    switch (kind) {
    case ActivationKind::swish: return x / (T(1) + std::exp(-x));
    case ActivationKind::tanh: return std::tanh(x);
    case ActivationKind::relu: return x > T(0) ? x : T(0);
    case ActivationKind::identity: break;
    }
    return x;
}

template <typename T>
inline T activation_derivative(ActivationKind kind, T x)
{
    switch (kind) {
    case ActivationKind::swish: {
        const T s = T(1) / (T(1) + std::exp(-x));
        return s * (T(1) + x * (T(1) - s));
    }
    case ActivationKind::tanh: {
        const T t = std::tanh(x);
        return T(1) - t * t;
    }
    case ActivationKind::relu: return x > T(0) ? T(1) : T(0);
    case ActivationKind::identity: break;
    }
    return T(1);
}

/// Vectorised in-place application on an array expression (Eigen array ops).
template <typename Derived>
inline void apply_activation(ActivationKind kind, Eigen::ArrayBase<Derived>& a)
{
    using Scalar = typename Derived::Scalar;
    switch (kind) {
    case ActivationKind::swish: a = a / (Scalar(1) + (-a).exp()); break;
    case ActivationKind::tanh: a = a.tanh(); break;
    case ActivationKind::relu: a = a.max(Scalar(0)); break;
    case ActivationKind::identity: break;
    }
}

/// Element-wise activation layer (no parameters).
class Activation : public Layer {
public:
    explicit Activation(ActivationKind kind) : m_kind(kind) { }

    ActivationKind kind() const { return m_kind; }
    std::string type_name() const override { return to_string(m_kind); }
    Index in_features() const override { return 0; }
    Index out_features() const override { return 0; }

    BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) override;
    BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) override;
    MatrixXd tangent(const MatrixXd& dX) const override;
    void describe(std::ostream& os) const override;
    std::unique_ptr<Layer> clone() const override { return std::make_unique<Activation>(*this); }

private:
    /// out = f'(X) ⊙ dX at the cached input X: dX of its shape, or of any number of columns
    /// when X is one sample. f' is evaluated per entry as it is multiplied (no temporary).
    void scale_by_derivative(const Eigen::Ref<const MatrixXd>& dX, Eigen::Ref<MatrixXd> out) const;

    ActivationKind m_kind;
    GrowingMatrix<double> m_input, m_output, m_input_grad;  ///< cached X; Y, dX
};

/// x·sigmoid(x) (torch.nn.SiLU).
class Swish final : public Activation {
public:
    Swish() : Activation(ActivationKind::swish) { }
    std::unique_ptr<Layer> clone() const override { return std::make_unique<Swish>(*this); }
};

} // namespace lb::nn
