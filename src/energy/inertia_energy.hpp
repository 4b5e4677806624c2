#pragma once
// Inertia term of implicit Euler as minimisation (Martin et al. 2011).
//
//   element   E_i = m_i / (2h²) |x_i − x̃_i|²   (one vertex per element)
//   mesh      E = 1/(2h²) (x − x̃)ᵀ M (x − x̃),  M = diag(m) ⊗ I₃ lumped,
//             x̃ = 2 x_{t−1} − x_{t−2} the inertial target (set each step)
//   Hessian   M / h² (constant, PSD)
#include "energy/energy.hpp"

namespace lb {

/// The inertial target x̃ = 2 x_{t−1} − x_{t−2}, column by column for matrices (an Eigen
/// expression, evaluated where it is assigned). The one formula: InertiaEnergy::set_previous
/// and the callers that keep x̃ themselves (the integrator trainer caches it per sample) use
/// it, so x̃ is the same bit for bit wherever it is formed.
template <typename Prev, typename Prev2>
auto inertial_target(const Eigen::MatrixBase<Prev>& x_prev, const Eigen::MatrixBase<Prev2>& x_prev2)
{
    return 2.0 * x_prev.derived() - x_prev2.derived();
}

class InertiaEnergy final : public ElementEnergy<1> {
public:
    /// @param masses  N lumped vertex masses (kg), non-negative
    /// @param dt      time step h (s)
    /// x̃ starts at zero: call set_x_tilde before evaluating.
    InertiaEnergy(VectorXd masses, double dt);

    std::string name() const override { return "inertia"; }
    /// One vectorised pass over the whole state (no per-vertex call): the training losses
    /// evaluate it once per sample.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;

    /// @param x_tilde  3N inertial target 2 x_{t−1} − x_{t−2}, xyz interleaved
    void set_x_tilde(const Eigen::Ref<const VectorXd>& x_tilde);
    /// x̃ = inertial_target(x_prev, x_prev2), formed in place (no temporary; both 3N).
    void set_previous(const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2);
    const VectorXd& x_tilde() const { return m_x_tilde; }
    const VectorXd& masses() const { return m_masses; }
    double dt() const { return m_dt; }

protected:
    double local_value(Index i, const ElementVector& xe) const override;
    ElementVector local_gradient(Index i, const ElementVector& xe) const override;
    ElementMatrix local_hessian(Index i, const ElementVector& xe) const override;

private:
    VectorXd m_masses;
    double m_dt;
    double m_inv_dt2;
    VectorXd m_dof_weights;  ///< m_i / h² per DOF (3N)
    VectorXd m_x_tilde;

    /// Throws Error naming caller unless size is 3N.
    void require_size(const char* caller, Index size) const;
};

} // namespace lb
