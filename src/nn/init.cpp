#include "nn/init.hpp"

#include <cmath>

namespace lb::nn {

void fill_uniform(Eigen::Ref<MatrixXd> m, double bound, Rng& rng)
{
    for (Index j = 0; j < m.cols(); ++j)
        for (Index i = 0; i < m.rows(); ++i) m(i, j) = rng.uniform(-bound, bound);
}

void init_linear_default(MatrixXd& weight, VectorXd& bias, Rng& rng)
{
    const Index fan_in = weight.cols();
    // kaiming_uniform_(a=√5): gain = √(2/(1+a²)) = √(1/3), bound = gain·√(3/fan_in) = 1/√fan_in.
    const double bound = fan_in > 0 ? 1.0 / std::sqrt(static_cast<double>(fan_in)) : 0.0;
    fill_uniform(weight, bound, rng);
    fill_uniform(bias, bound, rng);
}

} // namespace lb::nn
