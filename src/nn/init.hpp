#pragma once
// Parameter initialisation matching PyTorch's defaults, drawn from lb::Rng so that
// runs are reproducible from the configuration's seed.
#include "core/rng.hpp"
#include "core/types.hpp"

namespace lb::nn {

/// torch.nn.Linear's default: weight via kaiming_uniform_(a = √5), which is
/// U(−1/√fan_in, 1/√fan_in), and bias U(−1/√fan_in, 1/√fan_in).
/// @param weight  out × in, filled in column-major order
/// @param bias    out
void init_linear_default(MatrixXd& weight, VectorXd& bias, Rng& rng);

/// Fill with U(−bound, bound).
void fill_uniform(Eigen::Ref<MatrixXd> m, double bound, Rng& rng);

} // namespace lb::nn
