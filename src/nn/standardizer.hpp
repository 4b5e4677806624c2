#pragma once
// Per-feature standardisation of network inputs with training statistics:
//   x' = (x − mean) / std.
// std is the population standard deviation of the training data; features whose
// std is below `min_std` (constant features) get std = 1 so they pass through
// centred instead of being blown up. Saved with the network (see serialization.hpp)
// and folded into the first Linear of the float inference path.
#include "core/types.hpp"

namespace lb::nn {

class Standardizer {
public:
    static constexpr double default_min_std = 1e-8;

    Standardizer() = default;
    /// Identity map on `features` inputs.
    explicit Standardizer(Index features);
    Standardizer(VectorXd mean, VectorXd stddev);

    /// Fit to training data. @param X  features × samples (at least one sample)
    static Standardizer fit(const Eigen::Ref<const MatrixXd>& X, double min_std = default_min_std);

    /// @param X  features × B  @return (X − mean)/std
    MatrixXd apply(const Eigen::Ref<const MatrixXd>& X) const;
    /// The same into `out` (features × B, shaped by the caller).
    void apply(const Eigen::Ref<const MatrixXd>& X, Eigen::Ref<MatrixXd> out) const;
    /// Inverse map: X' ⊙ std + mean.
    MatrixXd invert(const Eigen::Ref<const MatrixXd>& X_standardized) const;
    /// Chain rule for input gradients: ∂L/∂x = (∂L/∂x') / std (column-wise).
    MatrixXd backward(const Eigen::Ref<const MatrixXd>& dX_standardized) const;
    /// The same into `out` (features × B, shaped by the caller).
    void backward(const Eigen::Ref<const MatrixXd>& dX_standardized, Eigen::Ref<MatrixXd> out) const;

    Index features() const { return m_mean.size(); }
    bool empty() const { return m_mean.size() == 0; }
    const VectorXd& mean() const { return m_mean; }
    const VectorXd& stddev() const { return m_std; }

private:
    VectorXd m_mean, m_std;
};

} // namespace lb::nn
