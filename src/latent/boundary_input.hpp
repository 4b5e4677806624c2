#pragma once
// The boundary parameters p_t the latent integrator takes (Li et al. 2025 §3.3,
// z_t = I(z_{t−1}, z_{t−2}, p_t, p_{t−1}, p_{t−2})):
//   velocity  p_t = the scene's parameters of frame t (the handle's velocity and angular
//             velocity, sim/dataset.hpp bc_params): the paper's, the default;
//   pose      p_t = [those parameters, c_t, R_t e_x, R_t e_y]: the Dirichlet targets' rigid
//             pose appended, (c_t, R_t) the least-squares rigid motion (core/rigid_motion.hpp)
//             from the Dirichlet vertices' rest positions to the frame's targets, the
//             rotation as its first two columns (6 numbers, continuous, unlike angles). A
//             collinear Dirichlet set (the cloth's two corners) has R_t = I.
// Why: the decoder sees positions relative to the boundary, so velocities alone leave the
// integrator to infer where the boundary is (e.g. the rotated rods' angle) from z.
#include <string>

#include "core/rigid_motion.hpp"
#include "core/types.hpp"
#include "sim/physics_model.hpp"

namespace lb {

enum class BoundaryInputKind { Velocity, Pose };
std::string to_string(BoundaryInputKind kind);
/// Throws ConfigError naming the accepted values.
BoundaryInputKind boundary_input_from_string(const std::string& name);

class BoundaryInput {
public:
    /// Numbers the pose appends: the centroid (3) and two rotation columns (6).
    static constexpr Index kPoseSize = 9;

    BoundaryInput() = default;
    /// @param kind             what p_t holds
    /// @param rest_targets     3B rest positions of the Dirichlet vertices, xyz interleaved
    ///                         (the pose's reference; unused for velocity)
    BoundaryInput(BoundaryInputKind kind, VectorXd rest_targets);
    /// The pose's reference from the physics: the rest positions of its Dirichlet vertices.
    BoundaryInput(BoundaryInputKind kind, const PhysicsSpec& physics);

    BoundaryInputKind kind() const { return m_kind; }
    const VectorXd& rest_targets() const { return m_rest_targets; }
    /// The size of p_t for P scene parameters.
    Index size(Index num_params) const { return num_params + (m_kind == BoundaryInputKind::Pose ? kPoseSize : 0); }

    /// p_t of one frame.
    /// @param params   P scene parameters of the frame
    /// @param targets  3B Dirichlet targets of the frame
    VectorXd of_frame(const Eigen::Ref<const VectorXd>& params, const Eigen::Ref<const VectorXd>& targets) const;
    /// The pose [c, R e_x, R e_y] (kPoseSize) of 3B Dirichlet targets.
    VectorXd pose(const Eigen::Ref<const VectorXd>& targets) const;

private:
    BoundaryInputKind m_kind = BoundaryInputKind::Velocity;
    VectorXd m_rest_targets;
    RestFrame m_rest_frame;  ///< of m_rest_targets
};

} // namespace lb
