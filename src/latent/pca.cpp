#include "latent/pca.hpp"

#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>

namespace lb {

double PcaBasis::explained_fraction() const
{
    if (total_variance <= 0.0) return 1.0;
    return std::min(1.0, variances.sum() / total_variance);
}

namespace {

void normalize_signs(MatrixXd& U)
{
    for (Index j = 0; j < U.cols(); ++j) {
        Index i_max = 0;
        U.col(j).cwiseAbs().maxCoeff(&i_max);
        if (U(i_max, j) < 0.0) U.col(j) *= -1.0;
    }
}

} // namespace

PcaBasis compute_pca(const MatrixXd& X, Index dim)
{
    const Index F = X.rows(), S = X.cols();
    if (S < 1 || F < 1) throw std::invalid_argument("compute_pca: empty data");
    if (dim < 1 || dim > F)
        throw std::invalid_argument("compute_pca: dim " + std::to_string(dim) + " outside [1, " + std::to_string(F) + "]");

    PcaBasis pca;
    pca.mean = X.rowwise().mean();
    const MatrixXd C = X.colwise() - pca.mean;
    pca.total_variance = C.squaredNorm() / double(S);
    pca.variances.resize(dim);

    if (S <= F) {
        MatrixXd G = MatrixXd::Zero(S, S);
        G.selfadjointView<Eigen::Lower>().rankUpdate(C.transpose());
        Eigen::SelfAdjointEigenSolver<MatrixXd> eig(G);  // ascending eigenvalues
        const VectorXd& lambda = eig.eigenvalues();
        const double lambda_max = std::max(lambda(S - 1), 0.0);
        for (Index k = 0; k < S; ++k) pca.rank += lambda(k) > kPcaRankTolerance * lambda_max && lambda(k) > 0.0;
        MatrixXd U = MatrixXd::Zero(F, dim);
        for (Index j = 0; j < dim; ++j) {
            const Index k = S - 1 - j;
            const double l = j < S ? lambda(k) : 0.0;
            if (j < S && l > kPcaRankTolerance * lambda_max && l > 0.0) {
                U.col(j) = C * eig.eigenvectors().col(k) / std::sqrt(l);
                pca.variances(j) = l / double(S);
            } else {
                pca.variances(j) = 0.0;  // no variance: any direction orthogonal to the rest
            }
        }
        // Re-orthonormalise in order; Q's column j spans U_1..U_j, sign so that Q_jᵀU_j ≥ 0.
        Eigen::HouseholderQR<MatrixXd> qr(U);
        MatrixXd Q = qr.householderQ() * MatrixXd::Identity(F, dim);
        const MatrixXd R = qr.matrixQR().topRows(dim).triangularView<Eigen::Upper>();
        for (Index j = 0; j < dim; ++j)
            if (R(j, j) < 0.0) Q.col(j) *= -1.0;
        pca.basis = std::move(Q);
    } else {
        MatrixXd G = MatrixXd::Zero(F, F);
        G.selfadjointView<Eigen::Lower>().rankUpdate(C);
        Eigen::SelfAdjointEigenSolver<MatrixXd> eig(G);
        const double lambda_max = std::max(eig.eigenvalues()(F - 1), 0.0);
        for (Index k = 0; k < F; ++k)
            pca.rank += eig.eigenvalues()(k) > kPcaRankTolerance * lambda_max && eig.eigenvalues()(k) > 0.0;
        pca.basis.resize(F, dim);
        for (Index j = 0; j < dim; ++j) {
            pca.basis.col(j) = eig.eigenvectors().col(F - 1 - j);
            pca.variances(j) = std::max(eig.eigenvalues()(F - 1 - j), 0.0) / double(S);
        }
    }
    normalize_signs(pca.basis);
    return pca;
}

} // namespace lb
