#pragma once
// Boundary-relative encodings (Li et al. 2025 §3.2): what the autoencoder sees.
//   rods:            features = x_i − x_root(i) for every non-root vertex (roots excluded);
//                    decoding re-applies the prescribed root positions.
//   cloth, solids:   features = x_i − mean_{j∈B} x_j for every vertex;
//                    decoding adds the mean of the prescribed Dirichlet targets.
// Decoding: x = P f + offset(bc_targets), so ∂L/∂f = Pᵀ ∂L/∂x (gradient_to_features).
// Rods: features are the non-root vertices in ascending vertex order; every vertex must
// belong to exactly one rod (mesh.rods) whose root (chain start) is a Dirichlet vertex.
// Cloth/solids: decoded Dirichlet vertices are not overwritten with their targets (the
// learning losses' penalty acts on them); for ground-truth frames they coincide.
#include <vector>

#include "sim/physics_model.hpp"

namespace lb {

class BcRelativeEncoding {
public:
    explicit BcRelativeEncoding(const PhysicsSpec& physics);

    /// F: 3(N − R) for rods, 3N otherwise.
    Index num_features() const { return m_num_features; }
    Index num_dofs() const { return m_num_dofs; }
    bool rod_relative() const { return m_rod_relative; }
    /// "rod_root" or "dirichlet_mean" (stored in autoencoder files).
    const char* kind_name() const { return m_rod_relative ? "rod_root" : "dirichlet_mean"; }
    const std::vector<int>& bc_indices() const { return m_bc_indices; }

    /// @param X  3N × S positions (one column per frame) @return F × S features
    MatrixXd to_features(const MatrixXd& X) const;
    /// @param F        F × S features
    /// @param targets  3B × S Dirichlet targets (xyz interleaved, one column per frame)
    /// @return 3N × S positions
    MatrixXd to_positions(const MatrixXd& F, const MatrixXd& targets) const;
    /// One frame without allocation (the inference path): x (3N) from features f (F,
    /// float or double) and the Dirichlet targets (3B).
    void to_positions_into(const Eigen::Ref<const VectorXd>& f, const Eigen::Ref<const VectorXd>& targets,
                           Eigen::Ref<VectorXd> x) const;
    void to_positions_into(const Eigen::Ref<const Eigen::VectorXf>& f, const Eigen::Ref<const VectorXd>& targets,
                           Eigen::Ref<VectorXd> x) const;
    /// Chain rule through to_positions: 3N × S position gradients → F × S.
    MatrixXd gradient_to_features(const MatrixXd& grad_x) const;

private:
    template <typename Scalar>
    void positions_of_frame(const Scalar* f, const double* targets, double* x) const;

    /// Mean of the Dirichlet vertices of one 3N position vector.
    Vector3d bc_mean(const Eigen::Ref<const VectorXd>& x) const;

    bool m_rod_relative = false;
    Index m_num_dofs = 0;
    Index m_num_features = 0;
    std::vector<int> m_bc_indices;
    /// Rods: for each feature vertex, (vertex, index of its root within bc_indices).
    std::vector<std::pair<int, int>> m_rod_vertices;
};

} // namespace lb
