#pragma once
// Gravitational potential.
//
//   element   E_i = −m_i g·x_i   (one vertex per element)
//   mesh      E = −Σ_i m_i g·x_i;  gradient −m_i g per vertex;  Hessian 0
// z-up convention: g = (0, 0, −9.81) m/s².
#include "energy/energy.hpp"

namespace lb {

class GravityEnergy final : public ElementEnergy<1> {
public:
    /// Standard gravity, z-up (m/s²).
    static Vector3d standard_gravity() { return {0.0, 0.0, -9.81}; }

    /// @param masses   N lumped vertex masses (kg)
    /// @param gravity  acceleration g (m/s²)
    GravityEnergy(VectorXd masses, const Vector3d& gravity);

    std::string name() const override { return "gravity"; }
    bool has_zero_hessian() const override { return true; }
    /// One vectorised pass over the whole state (no per-vertex call): the training losses
    /// evaluate it once per sample.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override;

    const Vector3d& gravity() const { return m_gravity; }
    const VectorXd& masses() const { return m_masses; }

protected:
    double local_value(Index i, const ElementVector& xe) const override;
    ElementVector local_gradient(Index i, const ElementVector& xe) const override;
    ElementMatrix local_hessian(Index i, const ElementVector& xe) const override;

private:
    VectorXd m_masses;
    Vector3d m_gravity;
    VectorXd m_weights;  ///< m_i g per vertex, xyz interleaved (3N): E = −m_weights · x
};

} // namespace lb
