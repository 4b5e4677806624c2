#include "energy/dihedral_angle.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace lb {
namespace {

using Vector9d = Eigen::Matrix<double, 9, 1>;
using Matrix9d = Eigen::Matrix<double, 9, 9>;

Matrix3d skew(const Vector3d& a)
{
    Matrix3d m;
    m << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
    return m;
}

// Set the symmetric pair of 3×3 blocks (i, j) and (j, i) of a 9×9 matrix over z = (e, u, v).
void set_pair(Matrix9d& H, int i, int j, const Matrix3d& block)
{
    H.block<3, 3>(3 * i, 3 * j) = block;
    H.block<3, 3>(3 * j, 3 * i) = block.transpose();
}

} // namespace

double wrap_angle(double angle)
{
    const double two_pi = 2.0 * M_PI;
    // fmod is the identity below 2π, and the differences of two angles in (−π, π] (the
    // hinge energy's θ − θ̄) always are: skip it there, same result, no division.
    if (!(std::abs(angle) < two_pi)) angle = std::fmod(angle, two_pi);
    return wrap_angle_difference(angle);
}

double dihedral_angle(const HingeVector& xe)
{
    return dihedral_angle(xe, nullptr, nullptr);
}

double dihedral_angle(const HingeVector& xe, HingeVector* gradient, HingeMatrix* hessian)
{
    const Vector3d x0 = xe.segment<3>(0);
    const Vector3d e = xe.segment<3>(3) - x0;
    const Vector3d u = xe.segment<3>(6) - x0;
    const Vector3d v = xe.segment<3>(9) - x0;
    if (hessian == nullptr) {
        // θ and ∇θ from the triangle normals N1 = e × u, N2 = v × e, with det = N1·v and
        // X = N1·N2 (Binet–Cauchy, as above). The opposite vertices move θ along their
        // triangle's normal at the rate 1/height = |e|/|N|:
        //   ∂θ/∂x2 = −|e| N1/|N1|²,  ∂θ/∂x3 = −|e| N2/|N2|²,
        // and the edge's ends follow from translation and rotation invariance, with
        // t_k = (x_k − x0)·e/|e|² the foot of the opposite vertex on the edge:
        //   ∂θ/∂x1 = −t2 ∂θ/∂x2 − t3 ∂θ/∂x3,  ∂θ/∂x0 = (t2 − 1) ∂θ/∂x2 + (t3 − 1) ∂θ/∂x3.
        // The same numbers as the z-route below (test_dihedral_angle compares them), in a
        // third of the time; written once, on plain arrays (dihedral_angle_gradient).
        double x[4][3], g[4][3];
        for (int a = 0; a < 4; ++a) {
            for (int i = 0; i < 3; ++i) x[a][i] = xe[3 * a + i];
        }
        const double theta = dihedral_angle_gradient(x, g);
        if (gradient != nullptr) {
            for (int a = 0; a < 4; ++a) {
                for (int i = 0; i < 3; ++i) (*gradient)[3 * a + i] = g[a][i];
            }
        }
        return theta;
    }

    const double ee = e.dot(e), eu = e.dot(u), ev = e.dot(v), uv = u.dot(v);
    const double len = std::sqrt(ee);
    const Vector3d u_x_v = u.cross(v);
    const double det = e.dot(u_x_v);
    const double Y = -len * det;
    const double X = eu * ev - ee * uv;
    const double theta = std::atan2(Y, X);

    // First derivatives over z = (e, u, v).
    Vector9d g_det, g_len, g_X;
    g_det << u_x_v, v.cross(e), e.cross(u);
    g_len << e / len, Vector3d::Zero(), Vector3d::Zero();
    const Vector9d g_Y = -(det * g_len + len * g_det);
    g_X << u * ev + v * eu - 2.0 * uv * e, e * ev - ee * v, e * eu - ee * u;
    const double r2 = X * X + Y * Y;
    // θ = atan2(Y, X):  ∇θ = (X ∇Y − Y ∇X) / (X² + Y²).
    const Vector9d g_theta = (X * g_Y - Y * g_X) / r2;

    // x = (x0, x1, x2, x3) ↦ z = (x1 − x0, x2 − x0, x3 − x0):  ∇_x = Sᵀ ∇_z.
    if (gradient != nullptr) {
        gradient->segment<3>(0) = -(g_theta.segment<3>(0) + g_theta.segment<3>(3) + g_theta.segment<3>(6));
        gradient->segment<9>(3) = g_theta;
    }

    // Second derivatives over z. Chain rule:
    //   ∇²θ = [X ∇²Y − Y ∇²X + ∇Y ∇Xᵀ − ∇X ∇Yᵀ] / r² − ∇θ (2X ∇X + 2Y ∇Y)ᵀ / r²,
    // with r² = X² + Y², whose antisymmetric parts cancel (we symmetrise only to
    // remove round-off). The pieces:
    //   det = e·(u×v):  ∂²/∂e∂u = −[v]×, ∂²/∂e∂v = [u]×, ∂²/∂u∂v = −[e]×, diagonal blocks 0
    //   |e|:            ∂²/∂e² = (I − êêᵀ)/|e|
    //   Y = −|e| det:   ∇²Y = −(det ∇²|e| + ∇|e| ∇detᵀ + ∇det ∇|e|ᵀ + |e| ∇²det)
    //   X = (e·u)(e·v) − (e·e)(u·v):
    //     ∂²/∂e² = u vᵀ + v uᵀ − 2(u·v) I,  ∂²/∂e∂u = (e·v) I + v eᵀ − 2 e vᵀ,
    //     ∂²/∂e∂v = (e·u) I + u eᵀ − 2 e uᵀ,  ∂²/∂u∂v = e eᵀ − (e·e) I,  ∂²/∂u² = ∂²/∂v² = 0.
    const Matrix3d I = Matrix3d::Identity();
    Matrix9d H_det = Matrix9d::Zero();
    set_pair(H_det, 0, 1, -skew(v));
    set_pair(H_det, 0, 2, skew(u));
    set_pair(H_det, 1, 2, -skew(e));
    Matrix9d H_len = Matrix9d::Zero();
    H_len.block<3, 3>(0, 0) = (I - e * e.transpose() / ee) / len;
    const Matrix9d H_Y =
        -(det * H_len + g_len * g_det.transpose() + g_det * g_len.transpose() + len * H_det);
    Matrix9d H_X = Matrix9d::Zero();
    H_X.block<3, 3>(0, 0) = u * v.transpose() + v * u.transpose() - 2.0 * uv * I;
    set_pair(H_X, 0, 1, ev * I + v * e.transpose() - 2.0 * e * v.transpose());
    set_pair(H_X, 0, 2, eu * I + u * e.transpose() - 2.0 * e * u.transpose());
    set_pair(H_X, 1, 2, e * e.transpose() - ee * I);

    Matrix9d H_theta = (X * H_Y - Y * H_X + g_Y * g_X.transpose() - g_X * g_Y.transpose()) / r2 -
                       g_theta * (2.0 / r2) * (X * g_X + Y * g_Y).transpose();
    H_theta = 0.5 * (H_theta + H_theta.transpose()).eval();

    // ∇²_x θ = Sᵀ ∇²_z θ S: x0's row/column blocks are minus the sums over z-blocks.
    HingeMatrix& H = *hessian;
    H.block<9, 9>(3, 3) = H_theta;
    for (int j = 0; j < 3; ++j) {
        const Matrix3d col_sum = H_theta.block<3, 3>(0, 3 * j) + H_theta.block<3, 3>(3, 3 * j) +
                                 H_theta.block<3, 3>(6, 3 * j);
        H.block<3, 3>(0, 3 + 3 * j) = -col_sum;
        H.block<3, 3>(3 + 3 * j, 0) = -col_sum.transpose();
    }
    H.block<3, 3>(0, 0) = -(H.block<3, 3>(0, 3) + H.block<3, 3>(0, 6) + H.block<3, 3>(0, 9));
    return theta;
}

} // namespace lb
