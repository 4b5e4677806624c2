#include "latent/boundary_input.hpp"

#include "core/error.hpp"
#include "core/rigid_motion.hpp"

namespace lb {

std::string to_string(BoundaryInputKind kind)
{
    return kind == BoundaryInputKind::Velocity ? "velocity" : "pose";
}

BoundaryInputKind boundary_input_from_string(const std::string& name)
{
    if (name == "velocity") return BoundaryInputKind::Velocity;
    if (name == "pose") return BoundaryInputKind::Pose;
    throw ConfigError("unknown boundary input '" + name + "' (expected velocity or pose)");
}

BoundaryInput::BoundaryInput(BoundaryInputKind kind, VectorXd rest_targets)
    : m_kind(kind), m_rest_targets(std::move(rest_targets)), m_rest_frame(m_rest_targets)
{
    if (m_rest_targets.size() % 3 != 0)
        throw Error("BoundaryInput: rest targets of size " + std::to_string(m_rest_targets.size()) +
                    " (expected 3B, xyz interleaved)");
}

BoundaryInput::BoundaryInput(BoundaryInputKind kind, const PhysicsSpec& physics)
    : BoundaryInput(kind, dirichlet_positions(physics.bc_indices, flatten(physics.mesh.rest_positions)))
{
}

VectorXd BoundaryInput::pose(const Eigen::Ref<const VectorXd>& targets) const
{
    if (targets.size() != m_rest_targets.size())
        throw Error("BoundaryInput: " + std::to_string(targets.size()) + " Dirichlet targets, expected " +
                    std::to_string(m_rest_targets.size()));
    const Matrix3d R = m_rest_frame.rotation(targets.data());
    VectorXd p(kPoseSize);
    p << m_rest_frame.centroid(targets.data()), R.col(0), R.col(1);
    return p;
}

VectorXd BoundaryInput::of_frame(const Eigen::Ref<const VectorXd>& params, const Eigen::Ref<const VectorXd>& targets) const
{
    if (m_kind == BoundaryInputKind::Velocity) return params;
    VectorXd p(size(params.size()));
    p << params, pose(targets);
    return p;
}

} // namespace lb
