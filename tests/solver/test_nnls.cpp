// Lawson–Hanson NNLS (solver/nnls.hpp): a consistent problem with a known non-negative
// solution that has zero entries, random problems against brute force over every
// active set, the Kuhn–Tucker conditions, and the Gram form fed incrementally.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <Eigen/QR>

#include "core/rng.hpp"
#include "solver/nnls.hpp"

namespace lb {
namespace {

MatrixXd random_matrix(Index rows, Index cols, Rng& rng)
{
    MatrixXd m(rows, cols);
    for (Index j = 0; j < cols; ++j)
        for (Index i = 0; i < rows; ++i) m(i, j) = rng.uniform(-1.0, 1.0);
    return m;
}

/// The exact NNLS minimiser for small n: the best feasible unconstrained solution over
/// every subset of free variables (the minimiser is one of them).
VectorXd brute_force(const MatrixXd& A, const VectorXd& b)
{
    const Index n = A.cols();
    VectorXd best = VectorXd::Zero(n);
    double best_f = b.squaredNorm();
    for (unsigned mask = 1; mask < (1u << n); ++mask) {
        std::vector<Index> cols;
        for (Index j = 0; j < n; ++j)
            if (mask & (1u << j)) cols.push_back(j);
        MatrixXd Ap(A.rows(), Index(cols.size()));
        for (size_t a = 0; a < cols.size(); ++a) Ap.col(Index(a)) = A.col(cols[a]);
        const VectorXd sp = Ap.colPivHouseholderQr().solve(b);
        if ((sp.array() < 0.0).any()) continue;
        const double f = (Ap * sp - b).squaredNorm();
        if (f < best_f) {
            best_f = f;
            best.setZero();
            for (size_t a = 0; a < cols.size(); ++a) best[cols[a]] = sp[Index(a)];
        }
    }
    return best;
}

TEST(Nnls, RecoversAKnownNonNegativeSolutionWithZeros)
{
    Rng rng(3);
    const MatrixXd A = random_matrix(40, 12, rng);
    VectorXd w_true(12);
    w_true << 0.5, 0.0, 2.0, 0.0, 0.0, 1.25, 3.0, 0.0, 0.1, 0.0, 0.7, 0.0;
    const VectorXd b = A * w_true;
    const NnlsResult r = nnls(A, b);
    ASSERT_TRUE(r.converged) << r.message;
    EXPECT_LT((r.w - w_true).lpNorm<Eigen::Infinity>(), 1e-10) << r.w.transpose();
    EXPECT_TRUE((r.w.array() >= 0.0).all());
}

TEST(Nnls, MatchesBruteForceAndKuhnTuckerOnRandomProblems)
{
    Rng rng(11);
    for (int trial = 0; trial < 20; ++trial) {
        const Index m = 15, n = 7;
        const MatrixXd A = random_matrix(m, n, rng);
        const VectorXd b = random_matrix(m, 1, rng).col(0);
        const NnlsResult r = nnls(A, b);
        ASSERT_TRUE(r.converged) << "trial " << trial << ": " << r.message;
        const VectorXd expected = brute_force(A, b);
        EXPECT_LT((r.w - expected).lpNorm<Eigen::Infinity>(), 1e-9) << "trial " << trial;
        // Kuhn–Tucker: w ≥ 0, gradient Aᵀ(b − Aw) ≤ 0, and = 0 where w > 0.
        const VectorXd grad = A.transpose() * (b - A * r.w);
        for (Index j = 0; j < n; ++j) {
            EXPECT_GE(r.w[j], 0.0);
            EXPECT_LE(grad[j], 1e-10);
            if (r.w[j] > 0.0) {
                EXPECT_NEAR(grad[j], 0.0, 1e-10);
            }
        }
    }
}

TEST(Nnls, ActiveBoundsMatchBruteForceAndShapeErrorsAreReported)
{
    Rng rng(5);
    const MatrixXd A = random_matrix(10, 3, rng);
    const VectorXd b = -A * Vector3d(1.0, 2.0, 0.5);  // mostly pushes w to its bound 0
    const NnlsResult r = nnls(A, b);
    ASSERT_TRUE(r.converged);
    const VectorXd expected = brute_force(A, b);
    EXPECT_LT((r.w - expected).lpNorm<Eigen::Infinity>(), 1e-10);
    const NnlsResult bad = nnls(A, VectorXd::Zero(4));
    EXPECT_FALSE(bad.converged);
    EXPECT_FALSE(bad.message.empty());
}

TEST(Nnls, GramFormEqualsTheMatrixForm)
{
    Rng rng(8);
    const MatrixXd A = random_matrix(30, 9, rng);
    const VectorXd b = random_matrix(30, 1, rng).col(0);
    const NnlsResult direct = nnls(A, b);
    const NnlsResult gram = nnls_gram(A.transpose() * A, A.transpose() * b);
    ASSERT_TRUE(direct.converged && gram.converged);
    EXPECT_LT((direct.w - gram.w).lpNorm<Eigen::Infinity>(), 1e-12);
}

} // namespace
} // namespace lb
