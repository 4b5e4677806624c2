#include "nn/network_derivatives.hpp"

#include <cassert>
#include <stdexcept>

#include "nn/linear.hpp"

namespace lb::nn {

VectorXd vjp(Sequential& net, const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& v)
{
    return vjp_batch(net, z, v).col(0);
}

MatrixXd vjp_batch(Sequential& net, const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& V)
{
    if (Z.cols() != V.cols() || V.rows() != net.out_features())
        throw std::invalid_argument("vjp_batch: V must be out_features × (columns of Z)");
    net.forward(Z, false);
    return net.backward(V, false);
}

VectorXd jvp(Sequential& net, const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& dz)
{
    return jvp_batch(net, z, dz).col(0);
}

MatrixXd jvp_batch(Sequential& net, const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& dZ)
{
    if (Z.cols() != dZ.cols() || Z.rows() != dZ.rows())
        throw std::invalid_argument("jvp_batch: Z and dZ must have the same shape");
    net.forward(Z, false);
    return net.tangent(dZ);
}

MatrixXd jacobian(Sequential& net, const Eigen::Ref<const VectorXd>& z)
{
    net.forward(z, false);
    return net.tangent(MatrixXd::Identity(z.size(), z.size()));
}

MatrixXd jacobian_rows(Sequential& net, const Eigen::Ref<const VectorXd>& z, const std::vector<Index>& rows,
                       JacobianMode mode)
{
    const Index in = z.size();
    const Index k = static_cast<Index>(rows.size());
    const Index out = net.out_features();
    for (Index r : rows)
        if (r < 0 || r >= out)
            throw std::out_of_range("jacobian_rows: row " + std::to_string(r) + " outside [0, " +
                                    std::to_string(out) + ")");
    if (mode == JacobianMode::automatic) mode = k <= in ? JacobianMode::reverse : JacobianMode::forward;

    const Index L = net.size();
    const auto* last = L > 0 ? dynamic_cast<const Linear*>(&net.layer(L - 1)) : nullptr;
    if (last != nullptr) {
        // Skip the last Linear's primal output: its Jacobian rows are just W(rows, :).
        const MatrixXd& W = last->weight();
        MatrixXd W_rows(k, W.cols());
        for (Index i = 0; i < k; ++i) W_rows.row(i) = W.row(rows[static_cast<std::size_t>(i)]);
        net.forward_range(z, false, 0, L - 1);
        if (mode == JacobianMode::reverse) {
            return net.backward_range(W_rows.transpose(), false, 0, L - 1).transpose();
        }
        return W_rows * net.tangent_range(MatrixXd::Identity(in, in), 0, L - 1);
    }

    net.forward(z, false);
    if (mode == JacobianMode::reverse) {
        MatrixXd seeds = MatrixXd::Zero(out, k);
        for (Index i = 0; i < k; ++i) seeds(rows[static_cast<std::size_t>(i)], i) = 1.0;
        return net.backward(seeds, false).transpose();
    }
    const MatrixXd T = net.tangent(MatrixXd::Identity(in, in));
    MatrixXd J(k, in);
    for (Index i = 0; i < k; ++i) J.row(i) = T.row(rows[static_cast<std::size_t>(i)]);
    return J;
}

} // namespace lb::nn
