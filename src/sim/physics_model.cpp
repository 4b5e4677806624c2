#include "sim/physics_model.hpp"

#include <cassert>

#include "core/error.hpp"
#include "core/hash.hpp"
#include "energy/dirichlet_penalty.hpp"
#include "energy/gravity_energy.hpp"
#include "energy/inertia_energy.hpp"
#include "energy/rod_bending.hpp"
#include "energy/rod_stretching.hpp"
#include "energy/shell_hinge_bending.hpp"
#include "energy/shell_membrane.hpp"
#include "energy/tet_stvk.hpp"

namespace lb {

PhysicsSpec physics_spec(const Scene& scene)
{
    return {scene.mesh, scene.material, scene.dt, scene.gravity, scene.bc_indices};
}

PhysicsModel::PhysicsModel(PhysicsSpec spec) : m_spec(std::move(spec))
{
    const Mesh& mesh = m_spec.mesh;
    const Material& mat = m_spec.material;
    m_masses = lumped_masses(mesh, mat.density, mat.thickness, mat.radius);
    switch (mesh.kind) {
    case MeshKind::Rods:
        m_elastic.push_back(std::make_shared<RodStretching>(mesh.rest_positions, mesh.elements,
                                                            mat.youngs_modulus, mat.radius));
        m_elastic.push_back(std::make_shared<RodBending>(mesh.rest_positions, rod_bending_stencils(mesh),
                                                         mat.youngs_modulus, mat.radius));
        break;
    case MeshKind::Shell:
        m_elastic.push_back(std::make_shared<ShellMembrane>(mesh.rest_positions, mesh.elements,
                                                            mat.youngs_modulus, mat.poisson_ratio,
                                                            mat.thickness));
        m_elastic.push_back(std::make_shared<ShellHingeBending>(
            mesh.rest_positions, shell_hinge_stencils(mesh.elements), mat.youngs_modulus,
            mat.poisson_ratio, mat.thickness));
        break;
    case MeshKind::Solid:
        m_elastic.push_back(std::make_shared<TetStVK>(mesh.rest_positions, mesh.elements,
                                                      mat.youngs_modulus, mat.poisson_ratio));
        break;
    }
    m_gravity = std::make_shared<GravityEnergy>(m_masses, m_spec.gravity);
    m_length_scale = mesh.bounding_box_diagonal();
    // The force that moves a vertex of mean mass by the bounding-box diagonal in one
    // step (plus its weight): a residual of ε·force_scale is a position error of
    // about ε·L per vertex in the inertia-dominated regime.
    const double mean_mass = m_masses.mean();
    m_force_scale = mean_mass * (m_spec.gravity.norm() + m_length_scale / (m_spec.dt * m_spec.dt));
    for (int i : m_spec.bc_indices) {
        if (i < 0 || i >= mesh.num_vertices()) throw Error("Dirichlet index out of range");
    }
}

VectorXi PhysicsModel::dof_to_unknown() const
{
    VectorXi map = VectorXi::Zero(num_dofs());
    for (int i : m_spec.bc_indices) map.segment<3>(3 * i).setConstant(-1);
    int next = 0;
    for (Index d = 0; d < map.size(); ++d) {
        if (map[d] >= 0) map[d] = next++;
    }
    return map;
}

VectorXd PhysicsModel::rest_state() const { return flatten(m_spec.mesh.rest_positions); }

double PhysicsModel::elastic_energy(const VectorXd& x) const
{
    double e = 0.0;
    for (const auto& term : m_elastic) e += term->value(x);
    return e;
}

double PhysicsModel::kinetic_energy(const VectorXd& x, const VectorXd& x_prev) const
{
    const double inv_h = 1.0 / m_spec.dt;
    double e = 0.0;
    for (Index i = 0; i < num_vertices(); ++i) {
        e += 0.5 * m_masses[i] * ((x.segment<3>(3 * i) - x_prev.segment<3>(3 * i)) * inv_h).squaredNorm();
    }
    return e;
}

void PhysicsModel::apply_bc(const MatrixX3d& targets, VectorXd& x) const
{
    // Row-major B×3: its storage is the xyz-interleaved 3B vector (flatten without the copy).
    overwrite_dirichlet(m_spec.bc_indices, Eigen::Map<const VectorXd>(targets.data(), targets.size()), x);
}

void overwrite_dirichlet(const std::vector<int>& bc_indices, const Eigen::Ref<const VectorXd>& targets,
                         Eigen::Ref<VectorXd> x)
{
    assert(targets.size() == 3 * Index(bc_indices.size()));
    for (size_t b = 0; b < bc_indices.size(); ++b) x.segment<3>(3 * Index(bc_indices[b])) = targets.segment<3>(3 * Index(b));
}

VectorXd dirichlet_positions(const std::vector<int>& bc_indices, const Eigen::Ref<const VectorXd>& x)
{
    VectorXd p(3 * Index(bc_indices.size()));
    for (size_t b = 0; b < bc_indices.size(); ++b) p.segment<3>(3 * Index(b)) = x.segment<3>(3 * Index(bc_indices[b]));
    return p;
}

double applied_penalty_weight(const PhysicsModel& model, double penalty_weight)
{
    return model.kind() == MeshKind::Rods ? 0.0 : penalty_weight;
}

IncrementalPotential::IncrementalPotential(const PhysicsModel& model, double penalty_weight)
{
    m_inertia = std::make_shared<InertiaEnergy>(model.masses(), model.dt());
    m_sum.add(m_inertia);
    for (const auto& term : model.elastic_terms()) m_sum.add(term);
    m_sum.add(model.gravity());
    if (penalty_weight > 0.0) {
        m_penalty = std::make_shared<DirichletPenalty>(model.bc_indices(), penalty_weight);
        m_sum.add(m_penalty);
    }
    m_inertia->set_x_tilde(model.rest_state());
}

void IncrementalPotential::set_previous(const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2)
{
    m_inertia->set_previous(x_prev, x_prev2);
}

void IncrementalPotential::set_x_tilde(const Eigen::Ref<const VectorXd>& x_tilde) { m_inertia->set_x_tilde(x_tilde); }

const VectorXd& IncrementalPotential::x_tilde() const { return m_inertia->x_tilde(); }

void IncrementalPotential::set_bc_targets(const Eigen::Ref<const MatrixX3d>& targets)
{
    if (m_penalty) m_penalty->set_targets(targets);
}

std::string physics_content_hash(const PhysicsSpec& p)
{
    Fnv1a64 h;
    h.add(int(p.mesh.kind)).add(MatrixXd(p.mesh.rest_positions)).add(p.mesh.elements);
    for (const auto& rod : p.mesh.rods) h.add(std::int64_t(rod.size())).add_bytes(rod.data(), rod.size() * sizeof(int));
    h.add(p.material.youngs_modulus).add(p.material.poisson_ratio).add(p.material.density);
    h.add(p.material.thickness).add(p.material.radius).add(p.dt);
    h.add(p.gravity.x()).add(p.gravity.y()).add(p.gravity.z());
    h.add(std::int64_t(p.bc_indices.size())).add_bytes(p.bc_indices.data(), p.bc_indices.size() * sizeof(int));
    return h.hex();
}

} // namespace lb
