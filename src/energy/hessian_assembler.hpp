#pragma once
// Sparse assembly of Σ_k w_k ∇²E_k restricted to the unknown DOFs, with the
// sparsity pattern and every element's scatter map computed once per scene.
//
// Only the lower triangle (row ≥ column) is stored: that is what the
// supernodal Cholesky reads.
#include <vector>

#include "energy/energy.hpp"

namespace lb {

class HessianAssembler {
public:
    /// @param dof_to_unknown  3N entries: index of each DOF among the unknowns, or −1 if
    ///                        the DOF is prescribed (Dirichlet) and removed from the system
    /// @param energies        the terms whose Hessians will be assembled, in the order
    ///                        assemble() will receive them
    HessianAssembler(const VectorXi& dof_to_unknown, const EnergySum& energies);

    Index num_unknowns() const { return m_num_unknowns; }
    /// Lower triangle of the assembled matrix; its pattern never changes.
    const SparseMatrixd& matrix() const { return m_matrix; }
    /// Values may be changed in place (e.g. a diagonal shift), never the pattern.
    SparseMatrixd& mutable_matrix() { return m_matrix; }

    /// Overwrite matrix() values with Σ_k w_k H_k(x) (element Hessians PSD-projected if
    /// `project_psd`). `energies` must have the same terms as at construction.
    void assemble(const EnergySum& energies, const VectorXd& x, bool project_psd);

    /// g_free[i] = g[dof] for each unknown DOF (restriction of a full gradient).
    VectorXd restrict(const VectorXd& full) const;
    /// restrict(full) written to `reduced` (resized; no allocation once it has the size).
    void restrict(const VectorXd& full, VectorXd& reduced) const;
    /// Add a vector over unknowns back onto the full DOF vector.
    void add_prolonged(const VectorXd& reduced, VectorXd& full) const;
    const VectorXi& dof_to_unknown() const { return m_dof_to_unknown; }

private:
    VectorXi m_dof_to_unknown;
    VectorXi m_unknown_to_dof;
    Index m_num_unknowns = 0;
    SparseMatrixd m_matrix;
    // Per term, per element, (3K)² value indices (−1: discarded entry).
    std::vector<std::vector<int>> m_scatter;
    std::vector<std::vector<double>> m_buffers;
};

} // namespace lb
