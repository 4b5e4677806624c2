#pragma once
// The physical system of a scene, shared by the full-space simulator, the
// learning losses and the metrics: lumped masses, the elastic terms of the
// object type, gravity, and the incremental potential of implicit Euler
//   E(x) = 1/(2h²)(x − x̃)ᵀM(x − x̃) + E_elastic(x) − Σ m_i g·x_i [+ w_bc Σ_B |x_i − x*_i|²],
//   x̃ = 2x_{t−1} − x_{t−2}.
#include <memory>
#include <string>
#include <vector>

#include "energy/energy.hpp"
#include "scene/scene.hpp"

namespace lb {

class InertiaEnergy;
class DirichletPenalty;

/// What defines the physics, independent of where it came from (scene file or dataset).
struct PhysicsSpec {
    Mesh mesh;
    Material material;
    double dt = 1.0 / 30.0;
    Vector3d gravity{0.0, 0.0, -9.81};
    std::vector<int> bc_indices;
};

PhysicsSpec physics_spec(const Scene& scene);

class PhysicsModel {
public:
    explicit PhysicsModel(PhysicsSpec spec);

    const PhysicsSpec& spec() const { return m_spec; }
    const Mesh& mesh() const { return m_spec.mesh; }
    MeshKind kind() const { return m_spec.mesh.kind; }
    double dt() const { return m_spec.dt; }
    const std::vector<int>& bc_indices() const { return m_spec.bc_indices; }
    Index num_vertices() const { return m_spec.mesh.num_vertices(); }
    Index num_dofs() const { return 3 * num_vertices(); }
    /// N lumped vertex masses (kg).
    const VectorXd& masses() const { return m_masses; }
    /// The elastic terms (rods: stretching + bending; shells: membrane + hinges; solids: StVK).
    const std::vector<std::shared_ptr<const Energy>>& elastic_terms() const { return m_elastic; }
    std::shared_ptr<const Energy> gravity() const { return m_gravity; }

    /// 3N map of DOF → unknown index, −1 on Dirichlet vertices (removed from the system).
    VectorXi dof_to_unknown() const;
    /// Rest positions as a 3N vector.
    VectorXd rest_state() const;
    /// Σ of the elastic terms at x.
    double elastic_energy(const VectorXd& x) const;
    /// ½ Σ m_i |(x_i − x_prev_i)/h|².
    double kinetic_energy(const VectorXd& x, const VectorXd& x_prev) const;
    /// Length scale (rest bounding-box diagonal, m) and force scale (N) used to make
    /// solver tolerances and residuals dimensionless: mean vertex mass × (|g| + L/h²).
    double length_scale() const { return m_length_scale; }
    double force_scale() const { return m_force_scale; }
    /// Overwrite the Dirichlet vertices of x with targets (B×3).
    void apply_bc(const MatrixX3d& targets, VectorXd& x) const;

private:
    PhysicsSpec m_spec;
    VectorXd m_masses;
    std::vector<std::shared_ptr<const Energy>> m_elastic;
    std::shared_ptr<const Energy> m_gravity;
    double m_length_scale = 1.0;
    double m_force_scale = 1.0;
};

/// Overwrite the Dirichlet vertices of x with their targets.
/// @param bc_indices  the B Dirichlet vertices
/// @param targets     3B targets x*_B, xyz interleaved, in the order of bc_indices
/// @param x           3N positions
void overwrite_dirichlet(const std::vector<int>& bc_indices, const Eigen::Ref<const VectorXd>& targets,
                         Eigen::Ref<VectorXd> x);
/// The Dirichlet vertices of x (its inverse): 3B positions, xyz interleaved, in the order
/// of bc_indices.
VectorXd dirichlet_positions(const std::vector<int>& bc_indices, const Eigen::Ref<const VectorXd>& x);

/// The boundary policy of reduced (latent and subspace) methods, stated once: their
/// decoders cannot pin vertices exactly in general, so cloth and solids add the Dirichlet
/// penalty w_bc Σ_B |x_i − x*_i|²; rods decode their roots exactly (BC-relative encoding,
/// hard roots), so no penalty (0). The full-space solver removes the Dirichlet DOF and
/// never uses a penalty.
/// @param penalty_weight  the configured w_bc (> 0)
/// @return the w_bc to build the IncrementalPotential with: 0 for rods, else penalty_weight
double applied_penalty_weight(const PhysicsModel& model, double penalty_weight);

/// Content hash (FNV-1a/64, hex) of what defines the physics: mesh, material, dt, gravity,
/// Dirichlet set. Part of the fingerprints of training checkpoints.
std::string physics_content_hash(const PhysicsSpec& spec);

/// The objective of one implicit-Euler step. Owns its inertia and penalty terms
/// (cheap), shares the model's elastic terms, so one instance per thread can be
/// evaluated concurrently (the learning losses do this over a batch).
class IncrementalPotential {
public:
    /// @param penalty_weight  w_bc of the Dirichlet penalty; 0 disables it (hard BC:
    ///                        the full-space solver and rods)
    IncrementalPotential(const PhysicsModel& model, double penalty_weight);

    /// x̃ = 2 x_prev − x_prev2 (both 3N).
    void set_previous(const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2);
    /// x̃ itself (3N), for callers that keep it.
    void set_x_tilde(const Eigen::Ref<const VectorXd>& x_tilde);
    /// Penalty targets x*_B (B×3); ignored without a penalty.
    void set_bc_targets(const Eigen::Ref<const MatrixX3d>& targets);

    const EnergySum& terms() const { return m_sum; }
    double value(const VectorXd& x) const { return m_sum.value(x); }
    VectorXd gradient(const VectorXd& x) const { return m_sum.gradient(x); }
    /// value(x), with gradient(x) written to g (resized), in one pass over the elements.
    double value_gradient(const VectorXd& x, VectorXd& g) const { return m_sum.value_gradient(x, g); }
    const VectorXd& x_tilde() const;
    bool has_penalty() const { return m_penalty != nullptr; }

private:
    std::shared_ptr<InertiaEnergy> m_inertia;
    std::shared_ptr<DirichletPenalty> m_penalty;
    EnergySum m_sum;  ///< x̃ lives in the inertia term only (set_previous writes it there)
};

} // namespace lb
