#pragma once
// Derivatives of a network's output with respect to its INPUT, in eval mode
// (BatchNorm uses running statistics), for one sample or a batch.
//
// All functions run a fresh eval-mode forward pass, so they overwrite the
// network's forward cache and must not be called between a training forward and
// its backward. Parameter gradients are not touched.
//
// Typical uses: the self-supervised loss needs J_D(z)ᵀ ∇E through the frozen
// decoder for every sample of a batch (vjp_batch); cubature baselines need the
// Jacobian rows of a few vertices (jacobian_rows).
#include <vector>

#include "nn/sequential.hpp"

namespace lb::nn {

/// J(z)ᵀ v.   @param z  in   @param v  out   @return in
VectorXd vjp(Sequential& net, const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& v);
/// Column i of the result is J(z_i)ᵀ v_i.   @param Z  in × B   @param V  out × B   @return in × B
/// (One eval forward of the batch and one backward; if the caller has just run
/// net.forward(Z, false) itself, net.backward(V, false) gives the same without the
/// second forward.)
MatrixXd vjp_batch(Sequential& net, const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& V);

/// J(z) dz by forward mode.   @param z, dz  in   @return out
VectorXd jvp(Sequential& net, const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& dz);
/// Column i: J(z_i) dz_i.   @param Z, dZ  in × B   @return out × B
MatrixXd jvp_batch(Sequential& net, const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& dZ);

/// Full Jacobian J(z), out × in (forward mode with the identity as tangents).
MatrixXd jacobian(Sequential& net, const Eigen::Ref<const VectorXd>& z);

enum class JacobianMode {
    automatic,  ///< reverse if rows.size() ≤ in, else forward
    forward,    ///< propagate in tangents (latent dim as batch)
    reverse     ///< back-propagate rows.size() adjoint seeds
};

/// Rows `rows` of J(z) (e.g. one vertex: {3i, 3i+1, 3i+2}), rows.size() × in.
///
/// Cost: both modes share one primal pass; when the last layer is a Linear (the
/// decoder's PCA layer, usually the largest) only the requested rows of its
/// weight are touched, so the big out × d_pca GEMV is skipped entirely. Forward
/// mode then costs ~in tangent passes through the remaining layers, reverse mode
/// ~rows.size() adjoint passes, so `automatic` picks reverse when rows.size() ≤ in
/// (one vertex: 3 rows vs latent 4–12).
MatrixXd jacobian_rows(Sequential& net, const Eigen::Ref<const VectorXd>& z, const std::vector<Index>& rows,
                       JacobianMode mode = JacobianMode::automatic);

} // namespace lb::nn
