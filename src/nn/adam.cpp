#include "nn/adam.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace lb::nn {

Adam::Adam(std::vector<ParameterRef> parameters, AdamOptions options)
    : m_parameters(std::move(parameters)), m_options(options)
{
    for (const auto& p : m_parameters) {
        m_state.m.push_back(MatrixXd::Zero(p.value.rows(), p.value.cols()));
        m_state.v.push_back(MatrixXd::Zero(p.value.rows(), p.value.cols()));
    }
}

void Adam::set_state(AdamState state)
{
    const std::size_t n = m_parameters.size();
    if (state.m.size() != n || state.v.size() != n)
        throw std::invalid_argument("Adam::set_state: " + std::to_string(state.m.size()) + "/" +
                                    std::to_string(state.v.size()) + " moments for " + std::to_string(n) +
                                    " parameters");
    for (std::size_t i = 0; i < n; ++i) {
        const auto& p = m_parameters[i].value;
        if (state.m[i].rows() != p.rows() || state.m[i].cols() != p.cols() || state.v[i].rows() != p.rows() ||
            state.v[i].cols() != p.cols())
            throw std::invalid_argument("Adam::set_state: moment shape mismatch for " + m_parameters[i].name);
    }
    if (state.step < 0) throw std::invalid_argument("Adam::set_state: negative step count");
    m_state = std::move(state);
}

void Adam::zero_grad()
{
    for (auto& p : m_parameters) p.grad.setZero();
}

void Adam::step()
{
    ++m_state.step;
    const double t = static_cast<double>(m_state.step);
    const double bias_correction1 = 1.0 - std::pow(m_options.beta1, t);
    const double bias_correction2 = 1.0 - std::pow(m_options.beta2, t);
    const double step_size = m_options.lr / bias_correction1;
    const double sqrt_bc2 = std::sqrt(bias_correction2);
    for (std::size_t i = 0; i < m_parameters.size(); ++i) {
        auto& p = m_parameters[i];
        auto g = p.grad.array();
        auto m = m_state.m[i].array();
        auto v = m_state.v[i].array();
        if (m_options.weight_decay != 0.0) {
            const Eigen::ArrayXXd gd = g + m_options.weight_decay * p.value.array();
            m = m_options.beta1 * m + (1.0 - m_options.beta1) * gd;
            v = m_options.beta2 * v + (1.0 - m_options.beta2) * gd.square();
        } else {
            m = m_options.beta1 * m + (1.0 - m_options.beta1) * g;
            v = m_options.beta2 * v + (1.0 - m_options.beta2) * g.square();
        }
        p.value.array() -= step_size * m / (v.sqrt() / sqrt_bc2 + m_options.eps);
    }
}

} // namespace lb::nn
