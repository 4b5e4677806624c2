#pragma once
// E(x) = Σ_k w_k E_k(x) as an Objective over the unknown DOFs of a mesh: the
// unknowns y (size U) are scattered into a full 3N state whose prescribed
// (Dirichlet) DOFs keep the values of the state given at construction, so
//   f(y) = E(x(y)),  ∇f = restrict(∇E),  ∇²f = the rows and columns of the unknowns.
// A view for one minimisation: it holds references to the assembler and the
// energies, which must outlive it.
#include "energy/energy.hpp"
#include "energy/hessian_assembler.hpp"
#include "solver/objective.hpp"

namespace lb {

/// The full-size vectors a FreeDofObjective works in. Kept by the caller across
/// minimisations (NewtonSolver does), they stop allocating once they have the size.
struct FreeDofBuffers {
    VectorXd x_full;         ///< 3N state, prescribed DOFs fixed
    VectorXd gradient_full;  ///< 3N gradient before restriction
};

class FreeDofObjective final : public Objective {
public:
    /// @param assembler  built for `energies`' terms (its pattern is the Hessian's)
    /// @param x_full     3N state; its prescribed DOFs are kept, its unknowns ignored
    /// @param buffers    storage to work in (must outlive the objective); nullptr: its own
    FreeDofObjective(HessianAssembler& assembler, const EnergySum& energies, const VectorXd& x_full,
                     FreeDofBuffers* buffers = nullptr);
    FreeDofObjective(const FreeDofObjective&) = delete;
    FreeDofObjective& operator=(const FreeDofObjective&) = delete;

    /// The unknowns of a full state (restriction).
    VectorXd unknowns(const VectorXd& x_full) const { return m_assembler.restrict(x_full); }
    void unknowns(const VectorXd& x_full, VectorXd& y) const { m_assembler.restrict(x_full, y); }
    /// The full state of unknowns y: prescribed DOFs from the construction state.
    const VectorXd& full_state(const Eigen::Ref<const VectorXd>& y);

    Index dimension() const override { return m_assembler.num_unknowns(); }
    double value(const Eigen::Ref<const VectorXd>& y) override;
    void gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g) override;
    double value_and_gradient(const Eigen::Ref<const VectorXd>& y, Eigen::Ref<VectorXd> g) override;
    HessianKind hessian_kind() const override { return HessianKind::Sparse; }
    SparseMatrixd& sparse_hessian(const Eigen::Ref<const VectorXd>& y, bool project_psd) override;

private:
    HessianAssembler& m_assembler;
    const EnergySum& m_energies;
    FreeDofBuffers m_own;     // used when the caller gives no buffers
    FreeDofBuffers& m_buffers;
    VectorXd& m_x;            // m_buffers.x_full
};

} // namespace lb
