#include "solver/free_dof_objective.hpp"

#include <cassert>

namespace lb {

FreeDofObjective::FreeDofObjective(HessianAssembler& assembler, const EnergySum& energies, const VectorXd& x_full,
                                   FreeDofBuffers* buffers)
    : m_assembler(assembler), m_energies(energies), m_buffers(buffers ? *buffers : m_own), m_x(m_buffers.x_full)
{
    assert(x_full.size() == assembler.dof_to_unknown().size());
    m_x = x_full;
}

const VectorXd& FreeDofObjective::full_state(const Eigen::Ref<const VectorXd>& y)
{
    assert(y.size() == dimension());
    const VectorXi& map = m_assembler.dof_to_unknown();
    for (Index dof = 0; dof < map.size(); ++dof) {
        if (map[dof] >= 0) m_x[dof] = y[map[dof]];
    }
    return m_x;
}

double FreeDofObjective::value(const Eigen::Ref<const VectorXd>& y) { return m_energies.value(full_state(y)); }

void FreeDofObjective::gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g)
{
    VectorXd& full = m_buffers.gradient_full;
    m_energies.gradient(full_state(y), full);
    const VectorXi& map = m_assembler.dof_to_unknown();
    for (Index dof = 0; dof < map.size(); ++dof) {
        if (map[dof] >= 0) g[map[dof]] = full[dof];
    }
}

double FreeDofObjective::value_and_gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g)
{
    gradient(y, g);
    return m_energies.value(m_x);  // m_x already holds x(y)
}

SparseMatrixd& FreeDofObjective::sparse_hessian(const Eigen::Ref<const VectorXd>& y, bool project_psd)
{
    m_assembler.assemble(m_energies, full_state(y), project_psd);
    return m_assembler.mutable_matrix();
}

} // namespace lb
