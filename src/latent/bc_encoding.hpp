#pragma once
// Boundary-relative encodings (Li et al. 2025 §3.2): what the autoencoder sees.
//   rods:            features = x_i − x_root(i) for every non-root vertex (roots excluded);
//                    decoding re-applies the prescribed root positions.
//   cloth, solids:   features = x_i − mean_{j∈B} x_j for every vertex;
//                    decoding adds the mean of the prescribed Dirichlet targets.
// Frame "translation" (the paper's) stops there. Frame "rigid" (issue 14) also removes the
// boundary's rotation: R is the best-fit (Kabsch) rotation taking the Dirichlet set's
// rest offsets p⁰_b − c⁰ to its current ones p_b − c, and the features are Rᵀ times the
// offsets above; decoding applies R of the prescribed targets. A rigid motion of the
// boundary then leaves the features of a rigidly carried body unchanged, so no latent
// dimension is spent on the boundary's pose. It needs a Dirichlet set that fixes a
// rotation (three non-collinear vertices; roots for rods).
// Decoding: x = P(R) f + offset(bc_targets), so ∂L/∂f = P(R)ᵀ ∂L/∂x (gradient_to_features,
// which therefore takes the targets too).
// Rods: features are the non-root vertices in ascending vertex order; every vertex must
// belong to exactly one rod (mesh.rods) whose root (chain start) is a Dirichlet vertex.
// Cloth/solids: decoded Dirichlet vertices are not overwritten with their targets (the
// learning losses' penalty acts on them); for ground-truth frames they coincide.
#include <string>
#include <vector>

#include "core/rigid_motion.hpp"
#include "sim/physics_model.hpp"

namespace lb {

/// The frame the features are expressed in (see above).
enum class EncodingFrame { translation, rigid };
/// "translation" / "rigid"; parse throws ConfigError naming the accepted values.
const char* encoding_frame_name(EncodingFrame frame);
EncodingFrame parse_encoding_frame(const std::string& text);

class BcRelativeEncoding {
public:
    /// Throws ConfigError if the rods are not rooted at Dirichlet vertices, or if the
    /// rigid frame is asked of a Dirichlet set that does not fix a rotation.
    explicit BcRelativeEncoding(const PhysicsSpec& physics, EncodingFrame frame = EncodingFrame::translation);

    /// F: 3(N − R) for rods, 3N otherwise.
    Index num_features() const { return m_num_features; }
    Index num_dofs() const { return m_num_dofs; }
    bool rod_relative() const { return m_rod_relative; }
    EncodingFrame frame() const { return m_frame; }
    /// "rod_root", "dirichlet_mean", "rod_root_rigid" or "dirichlet_rigid" (stored in
    /// autoencoder files).
    const char* kind_name() const;
    const std::vector<int>& bc_indices() const { return m_bc_indices; }

    /// @param X  3N × S positions (one column per frame) @return F × S features
    MatrixXd to_features(const MatrixXd& X) const;
    /// @param F        F × S features
    /// @param targets  3B × S Dirichlet targets (xyz interleaved, one column per frame)
    /// @return 3N × S positions
    MatrixXd to_positions(const Eigen::Ref<const MatrixXd>& F, const Eigen::Ref<const MatrixXd>& targets) const;
    /// The same into X (3N × S, shaped by the caller; no allocation), from double or
    /// single-precision features (the float32 decoder's output), each feature widened
    /// exactly: the positions equal those of F.cast<double>().
    void to_positions(const Eigen::Ref<const MatrixXd>& F, const Eigen::Ref<const MatrixXd>& targets,
                      Eigen::Ref<MatrixXd> X) const;
    void to_positions(const Eigen::Ref<const Eigen::MatrixXf>& F, const Eigen::Ref<const MatrixXd>& targets,
                      Eigen::Ref<MatrixXd> X) const;
    /// One frame without allocation (the inference path): x (3N) from features f (F,
    /// float or double) and the Dirichlet targets (3B).
    void to_positions_into(const Eigen::Ref<const VectorXd>& f, const Eigen::Ref<const VectorXd>& targets,
                           Eigen::Ref<VectorXd> x) const;
    void to_positions_into(const Eigen::Ref<const Eigen::VectorXf>& f, const Eigen::Ref<const VectorXd>& targets,
                           Eigen::Ref<VectorXd> x) const;
    /// Chain rule through to_positions at the same targets (3B × S; the rigid frame's
    /// R depends on them): 3N × S position gradients → F × S.
    MatrixXd gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& targets) const;
    /// The same into G (F × S, shaped by the caller; no allocation), in double or rounded
    /// to single precision (the float32 decoder's VJP input).
    void gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& targets,
                              Eigen::Ref<MatrixXd> G) const;
    void gradient_to_features(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& targets,
                              Eigen::Ref<Eigen::MatrixXf> G) const;
    /// The rigid frame's rotation for the Dirichlet positions `p` (3B, xyz interleaved);
    /// the identity in the translation frame.
    Matrix3d frame_rotation(const double* p) const;

private:
    template <typename Scalar>
    void positions_of_frame(const Scalar* f, const double* targets, double* x) const;
    template <typename Scalar>
    void positions_of_columns(const Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>& F,
                              const Eigen::Ref<const MatrixXd>& targets, Eigen::Ref<MatrixXd> X) const;
    /// gradient_to_features into G of either precision; shapes checked.
    template <typename Scalar>
    void gradient_into(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& targets,
                       Eigen::Ref<Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>> G) const;

    /// Mean of the Dirichlet vertices of one 3N position vector.
    Vector3d bc_mean(const Eigen::Ref<const VectorXd>& x) const;

    bool m_rod_relative = false;
    EncodingFrame m_frame = EncodingFrame::translation;
    RestFrame m_rest_frame;  ///< the Dirichlet set at rest (rigid frame only)
    Index m_num_dofs = 0;
    Index m_num_features = 0;
    std::vector<int> m_bc_indices;
    /// Rods: for each feature vertex, (vertex, index of its root within bc_indices).
    std::vector<std::pair<int, int>> m_rod_vertices;
};

} // namespace lb
