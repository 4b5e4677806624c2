#pragma once
// An ordered container of layers (torch.nn.Sequential). Children are named by
// their index, so parameters read "0.weight", "1.running_mean", ... under the
// caller's prefix (e.g. "decoder.").
//
// Layers are held by pointer: moving a Sequential keeps every ParameterRef (and
// an Adam built on them) valid; copying makes an independent deep copy.
#include <vector>

#include "nn/layer.hpp"

namespace lb::nn {

class Sequential final : public Layer {
public:
    Sequential() = default;
    Sequential(const Sequential& other);
    Sequential& operator=(const Sequential& other);
    Sequential(Sequential&&) noexcept = default;
    Sequential& operator=(Sequential&&) noexcept = default;

    /// Append a layer; throws std::invalid_argument if its in_features does not
    /// match the current output width (when both are known).
    Sequential& add(std::unique_ptr<Layer> layer);
    template <typename L, typename... Args>
    L& emplace(Args&&... args)
    {
        auto layer = std::make_unique<L>(std::forward<Args>(args)...);
        L& ref = *layer;
        add(std::move(layer));
        return ref;
    }

    Index size() const { return static_cast<Index>(m_layers.size()); }
    bool empty() const { return m_layers.empty(); }
    Layer& layer(Index i) { return *m_layers[static_cast<std::size_t>(i)]; }
    const Layer& layer(Index i) const { return *m_layers[static_cast<std::size_t>(i)]; }

    std::string type_name() const override { return "Sequential"; }
    Index in_features() const override;
    Index out_features() const override;

    /// The last layer's output (a copy in the network's own buffer when it has no layers).
    BatchView forward(const Eigen::Ref<const MatrixXd>& X, bool training) override;
    BatchView backward(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients = true) override;
    MatrixXd tangent(const MatrixXd& dX) const override;

    /// Forward through layers [begin, end) only (used by jacobian_rows).
    BatchView forward_range(const Eigen::Ref<const MatrixXd>& X, bool training, Index begin, Index end);
    /// Backward through layers [begin, end) in reverse order.
    BatchView backward_range(const Eigen::Ref<const MatrixXd>& dY, bool accumulate_parameter_gradients, Index begin,
                             Index end);
    MatrixXd tangent_range(const MatrixXd& dX, Index begin, Index end) const;

    void collect_parameters(const std::string& prefix, std::vector<ParameterRef>& out) override;
    void collect_buffers(const std::string& prefix, std::vector<BufferRef>& out) override;
    /// {"type": "Sequential", "layers": [...]}
    void describe(std::ostream& os) const override;
    std::unique_ptr<Layer> clone() const override { return std::make_unique<Sequential>(*this); }

    /// All parameters / buffers named with `prefix` (e.g. "decoder.").
    std::vector<ParameterRef> parameters(const std::string& prefix = "");
    std::vector<BufferRef> buffers(const std::string& prefix = "");
    Index num_parameters();
    void zero_grad();

private:
    std::vector<std::unique_ptr<Layer>> m_layers;
    GrowingMatrix<double> m_passthrough;  ///< an empty range's output: a copy of its input
};

} // namespace lb::nn
