#include "nn/sequential.hpp"

#include <new>
#include <stdexcept>
#include <utility>

namespace lb::nn {

Sequential::Sequential(const Sequential& other)
{
    m_layers.reserve(other.m_layers.size());
    for (const auto& l : other.m_layers) m_layers.push_back(l->clone());
}

Sequential& Sequential::operator=(const Sequential& other)
{
    if (this != &other) {
        Sequential copy(other);
        *this = std::move(copy);
    }
    return *this;
}

Sequential& Sequential::add(std::unique_ptr<Layer> layer)
{
    const Index current = out_features();
    const Index incoming = layer->in_features();
    if (current != 0 && incoming != 0 && current != incoming) {
        throw std::invalid_argument("Sequential::add: layer " + std::to_string(m_layers.size()) + " (" +
                                    layer->type_name() + ") expects " + std::to_string(incoming) +
                                    " inputs but the network produces " + std::to_string(current));
    }
    m_layers.push_back(std::move(layer));
    return *this;
}

Index Sequential::in_features() const
{
    for (const auto& l : m_layers)
        if (l->in_features() != 0) return l->in_features();
    return 0;
}

Index Sequential::out_features() const
{
    for (auto it = m_layers.rbegin(); it != m_layers.rend(); ++it)
        if ((*it)->out_features() != 0) return (*it)->out_features();
    return 0;
}

namespace {
/// Point `view` at `next` (an Eigen::Map is re-seated by placement new; assigning to it
/// would copy the coefficients).
void reseat(BatchView& view, const BatchView& next) { new (&view) BatchView(next.data(), next.rows(), next.cols()); }
} // namespace

BatchView Sequential::forward_range(const Eigen::Ref<const MatrixXd>& X, bool training, Index begin, Index end)
{
    if (begin >= end) {
        m_passthrough.resize(X.rows(), X.cols()) = X;
        return std::as_const(m_passthrough).view();
    }
    BatchView Y = layer(begin).forward(X, training);
    for (Index i = begin + 1; i < end; ++i) reseat(Y, layer(i).forward(Y, training));
    return Y;
}

BatchView Sequential::backward_range(const Eigen::Ref<const MatrixXd>& dY, bool accumulate, Index begin, Index end)
{
    if (begin >= end) {
        m_passthrough.resize(dY.rows(), dY.cols()) = dY;
        return std::as_const(m_passthrough).view();
    }
    BatchView d = layer(end - 1).backward(dY, accumulate);
    for (Index i = end - 2; i >= begin; --i) reseat(d, layer(i).backward(d, accumulate));
    return d;
}

MatrixXd Sequential::tangent_range(const MatrixXd& dX, Index begin, Index end) const
{
    MatrixXd t = dX;
    for (Index i = begin; i < end; ++i) t = layer(i).tangent(t);
    return t;
}

BatchView Sequential::forward(const Eigen::Ref<const MatrixXd>& X, bool training)
{
    return forward_range(X, training, 0, size());
}

BatchView Sequential::backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate)
{
    return backward_range(dY, accumulate, 0, size());
}

MatrixXd Sequential::tangent(const MatrixXd& dX) const { return tangent_range(dX, 0, size()); }

void Sequential::collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out)
{
    for (std::size_t i = 0; i < m_layers.size(); ++i)
        m_layers[i]->collect_parameters(prefix + std::to_string(i) + ".", out);
}

void Sequential::collect_buffers(const std::string& prefix, std::vector<BufferRef>& out)
{
    for (std::size_t i = 0; i < m_layers.size(); ++i)
        m_layers[i]->collect_buffers(prefix + std::to_string(i) + ".", out);
}

void Sequential::describe(std::ostream& os) const
{
    os << "{\"type\": \"Sequential\", \"layers\": [";
    for (std::size_t i = 0; i < m_layers.size(); ++i) {
        if (i) os << ", ";
        m_layers[i]->describe(os);
    }
    os << "]}";
}

std::vector<ParameterRef> Sequential::parameters(const std::string& prefix)
{
    std::vector<ParameterRef> out;
    collect_parameters(prefix, out);
    return out;
}

std::vector<BufferRef> Sequential::buffers(const std::string& prefix)
{
    std::vector<BufferRef> out;
    collect_buffers(prefix, out);
    return out;
}

Index Sequential::num_parameters()
{
    Index n = 0;
    for (const auto& p : parameters()) n += p.value.size();
    return n;
}

void Sequential::zero_grad()
{
    for (auto& p : parameters()) p.grad.setZero();
}

} // namespace lb::nn
