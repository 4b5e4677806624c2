#include "nn/standardizer.hpp"

#include <cassert>
#include <stdexcept>

namespace lb::nn {

Standardizer::Standardizer(Index features) : m_mean(VectorXd::Zero(features)), m_std(VectorXd::Ones(features)) { }

Standardizer::Standardizer(VectorXd mean, VectorXd stddev) : m_mean(std::move(mean)), m_std(std::move(stddev))
{
    if (m_mean.size() != m_std.size()) throw std::invalid_argument("Standardizer: mean and std sizes differ");
    if ((m_std.array() <= 0.0).any()) throw std::invalid_argument("Standardizer: std must be positive");
}

Standardizer Standardizer::fit(const Eigen::Ref<const MatrixXd>& X, double min_std)
{
    if (X.cols() < 1) throw std::invalid_argument("Standardizer::fit: no samples");
    VectorXd mean = X.rowwise().mean();
    VectorXd stddev = ((X.colwise() - mean).array().square().rowwise().mean()).sqrt();
    for (Index i = 0; i < stddev.size(); ++i)
        if (!(stddev[i] >= min_std)) stddev[i] = 1.0;
    return {std::move(mean), std::move(stddev)};
}

MatrixXd Standardizer::apply(const Eigen::Ref<const MatrixXd>& X) const
{
    MatrixXd out(X.rows(), X.cols());
    apply(X, out);
    return out;
}

void Standardizer::apply(const Eigen::Ref<const MatrixXd>& X, Eigen::Ref<MatrixXd> out) const
{
    assert(X.rows() == features() && out.rows() == X.rows() && out.cols() == X.cols());
    out = ((X.colwise() - m_mean).array().colwise() / m_std.array()).matrix();
}

MatrixXd Standardizer::invert(const Eigen::Ref<const MatrixXd>& X) const
{
    return ((X.array().colwise() * m_std.array()).colwise() + m_mean.array()).matrix();
}

MatrixXd Standardizer::backward(const Eigen::Ref<const MatrixXd>& dX) const
{
    MatrixXd out(dX.rows(), dX.cols());
    backward(dX, out);
    return out;
}

void Standardizer::backward(const Eigen::Ref<const MatrixXd>& dX, Eigen::Ref<MatrixXd> out) const
{
    assert(out.rows() == dX.rows() && out.cols() == dX.cols());
    out = (dX.array().colwise() / m_std.array()).matrix();
}

} // namespace lb::nn
