#pragma once
// The least-squares rigid motion between two point sets (Kabsch 1976): the boundary's rigid
// motion of the free-DOF kinetic energy (eval/metrics.hpp) and the boundary pose an
// integrator may take as input (latent/boundary_input.hpp).
#include "core/types.hpp"

namespace lb {

/// A rigid motion p ↦ R (p − from_centroid) + to_centroid.
struct RigidMotion {
    Matrix3d rotation = Matrix3d::Identity();
    Vector3d from_centroid = Vector3d::Zero();
    Vector3d to_centroid = Vector3d::Zero();
    Vector3d apply(const Vector3d& p) const { return rotation * (p - from_centroid) + to_centroid; }
};

/// The rotation R maximising tr(R H) for the cross-covariance H = Σ_k p_k q_kᵀ of centred
/// point sets p (from) and q (to): R p_k ≈ q_k (Kabsch, reflection corrected). The identity
/// if the points are collinear (|σ₂| ≤ 1e-9 |σ₁|: a rotation about their line is free).
/// Fixed-size: allocates nothing.
Matrix3d kabsch_rotation(const Matrix3d& H);

/// The rest shape of a point set, for fitting the rotation and centroid of its later poses
/// without allocating: the boundary's rigid frame of the encoding (latent/bc_encoding.hpp)
/// and the boundary pose an integrator may take as input (latent/boundary_input.hpp).
class RestFrame {
public:
    RestFrame() = default;
    /// @param rest  3K rest positions, xyz interleaved
    explicit RestFrame(const Eigen::Ref<const VectorXd>& rest);

    Index size() const { return m_offsets.cols(); }
    /// Whether the rest points fix a rotation: K ≥ 3 and not collinear.
    bool fixes_rotation() const;
    /// The least-squares rotation R with R (p⁰_k − c⁰) ≈ p_k − c for the 3K positions `p`
    /// (Kabsch; the identity if the rest points are collinear).
    Matrix3d rotation(const double* p) const;
    /// The centroid c of the 3K positions `p`.
    Vector3d centroid(const double* p) const;

private:
    Eigen::Matrix3Xd m_offsets;  ///< p⁰_k − c⁰, one column per point
};

/// Least-squares rigid motion taking the points `from` to `to` (each K×3, Kabsch with
/// reflection correction). Collinear or single points (rotation undetermined): the
/// translation of the centroid only. No points: the identity.
RigidMotion fit_rigid_motion(const MatrixX3d& from, const MatrixX3d& to);

} // namespace lb
