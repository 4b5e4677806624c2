#pragma once
// The autoencoder's decoder split at its last (PCA) layer, the way Fulton et al. 2019
// evaluate it at run time:
//   s    = g(z)                       inner network (every decoder layer but the last), d_pca
//   x(z) = U s + c(x*_B)              U = P W (3N × d_pca), c(t) = P b + A t
// with W, b the last Linear layer's weight and bias, P the feature → position map of the
// BC-relative encoding and A t its offset, linear in the Dirichlet targets t (3B):
// the mean of the targets for cloth and solids, each rod's root for rods (rows of U for
// rod roots are zero: roots are decoded exactly). Because x is affine in s, the inertia
// and gravity of implicit Euler reduce to d_pca × d_pca and d_pca-sized terms computed
// once here (UᵀMU, UᵀM g, UᵀMA), and any subset of vertices decodes from rows of U.
#include <memory>

#include "latent/autoencoder.hpp"
#include "nn/sequential.hpp"
#include "sim/physics_model.hpp"

namespace lb {

class PcaSplitDecoder {
public:
    /// Copies the decoder's layers (the autoencoder is not kept). Throws Error if the
    /// decoder's last layer is not Linear or the model does not match the autoencoder.
    PcaSplitDecoder(Autoencoder& autoencoder, const PhysicsModel& model);

    Index latent_dim() const { return m_latent_dim; }
    Index pca_dim() const { return m_U.cols(); }
    Index num_dofs() const { return m_U.rows(); }

    /// s = g(z) (eval mode); caches what vjp() needs.
    VectorXd inner(const Eigen::Ref<const VectorXd>& z);
    /// J_g(z)ᵀ v at the z of the last inner() call.   @param v  d_pca   @return latent
    VectorXd vjp(const Eigen::Ref<const VectorXd>& v);
    /// J_g(z) (d_pca × latent), forward mode; overwrites the cache of inner().
    MatrixXd inner_jacobian(const Eigen::Ref<const VectorXd>& z);

    /// U (3N × d_pca).
    const MatrixXd& basis() const { return m_U; }
    /// c(t) = P b + A t (3N) into c.   @param targets  3B Dirichlet targets
    void offset_into(const Eigen::Ref<const VectorXd>& targets, Eigen::Ref<VectorXd> c) const;
    /// A t (3N): the offset without the bias P b.
    void target_offset_into(const Eigen::Ref<const VectorXd>& targets, Eigen::Ref<VectorXd> c) const;

    /// UᵀMU (d_pca × d_pca), M the lumped mass matrix.
    const MatrixXd& mass_pca() const { return m_UtMU; }
    /// UᵀMA (d_pca × 3B): the inertia coupling of the Dirichlet targets' acceleration.
    const MatrixXd& mass_targets() const { return m_UtMA; }
    /// UᵀM g (d_pca), g the gravity acceleration at every vertex.
    const VectorXd& gravity_pca() const { return m_UtMg; }
    /// M g (3N).
    const VectorXd& mass_gravity() const { return m_Mg; }

private:
    Index m_latent_dim = 0;
    nn::Sequential m_inner;
    BcRelativeEncoding m_encoding;
    VectorXd m_bias;  ///< b (F)
    MatrixXd m_U, m_UtMU, m_UtMA;
    VectorXd m_UtMg, m_Mg, m_masses3;
};

} // namespace lb
