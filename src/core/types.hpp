#pragma once
// Shared scalar, vector and matrix types. Glossary used across latentbench:
//   x               3N positions, xyz interleaved (vertex i at x[3i..3i+2])
//   rest_positions  N×3 rest (material) positions X
//   x_tilde         inertial target 2 x_{t-1} − x_{t-2}
//   dt              time step h (s)
//   F, psi          deformation gradient, energy density
//   z               latent code;  bc  boundary condition (Dirichlet)
#include <Eigen/Core>
#include <Eigen/SparseCore>

namespace lb {

using Index = Eigen::Index;
using VectorXd = Eigen::VectorXd;
using VectorXf = Eigen::VectorXf;
using VectorXi = Eigen::VectorXi;
using MatrixXd = Eigen::MatrixXd;
using MatrixXf = Eigen::MatrixXf;
using MatrixXi = Eigen::MatrixXi;
using MatrixX3d = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Vector3d = Eigen::Vector3d;
using Matrix3d = Eigen::Matrix3d;
using SparseMatrixd = Eigen::SparseMatrix<double>;

/// View a 3N position vector as an N×3 row-major matrix (no copy).
inline Eigen::Map<const MatrixX3d> as_rows(const VectorXd& x)
{
    return {x.data(), x.size() / 3, 3};
}
inline Eigen::Map<MatrixX3d> as_rows(VectorXd& x) { return {x.data(), x.size() / 3, 3}; }

/// Flatten an N×3 matrix into a 3N xyz-interleaved vector.
inline VectorXd flatten(const Eigen::Ref<const MatrixX3d>& v)
{
    return Eigen::Map<const VectorXd>(v.data(), v.size());
}

} // namespace lb
