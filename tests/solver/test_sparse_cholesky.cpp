// SparseCholesky: solves, reports CHOLMOD's factor statistics, and leaves OpenMP's
// max-active-levels as it found it (CHOLMOD's own loops run serially inside it; a lost
// restore would serialise every later parallel loop of the process).
#include <gtest/gtest.h>

#include <omp.h>

#include <vector>

#include "solver/sparse_cholesky.hpp"

namespace lb {
namespace {

/// Lower triangle of the 7-point Laplacian on an n³ grid plus `shift`·I.
SparseMatrixd grid_laplacian(int n, double shift)
{
    const auto id = [n](int i, int j, int k) { return (i * n + j) * n + k; };
    std::vector<Eigen::Triplet<double>> t;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                const int r = id(i, j, k);
                t.emplace_back(r, r, 6.0 + shift);
                if (i > 0) t.emplace_back(r, id(i - 1, j, k), -1.0);
                if (j > 0) t.emplace_back(r, id(i, j - 1, k), -1.0);
                if (k > 0) t.emplace_back(r, id(i, j, k - 1), -1.0);
            }
    SparseMatrixd lower(n * n * n, n * n * n);
    lower.setFromTriplets(t.begin(), t.end());
    return lower;
}

TEST(SparseCholesky, SolvesAndReportsTheFactor)
{
    const SparseMatrixd lower = grid_laplacian(12, 0.1);
    SparseCholesky llt;
    ASSERT_EQ(llt.factor_nonzeros(), 0.0);
    llt.analyze(lower);
    ASSERT_EQ(llt.factorize(lower), FactorStatus::Success) << llt.message();
    EXPECT_GE(llt.factor_nonzeros(), double(lower.nonZeros()));  // fill-in only adds
    EXPECT_GT(llt.factorization_flops(), llt.factor_nonzeros());
    const VectorXd b = VectorXd::LinSpaced(lower.rows(), -1.0, 2.0);
    VectorXd x;
    llt.solve(b, x);
    const SparseMatrixd full = lower.selfadjointView<Eigen::Lower>();
    EXPECT_LT((full * x - b).norm(), 1e-12 * b.norm());
}

TEST(SparseCholesky, ReportsAnIndefiniteMatrix)
{
    const SparseMatrixd lower = grid_laplacian(4, -7.0);  // diagonal -1: not positive definite
    SparseCholesky llt;
    EXPECT_EQ(llt.factorize(lower), FactorStatus::NotPositiveDefinite);
    EXPECT_FALSE(llt.message().empty());
}

TEST(SparseCholesky, LeavesOpenMpNestingAsItFoundIt)
{
    const SparseMatrixd lower = grid_laplacian(10, 0.1);
    const VectorXd b = VectorXd::Ones(lower.rows());
    for (const int levels : {1, 3}) {
        omp_set_max_active_levels(levels);
        SparseCholesky llt;
        llt.analyze(lower);
        ASSERT_EQ(llt.factorize(lower), FactorStatus::Success);
        VectorXd x;
        llt.solve(b, x);
        EXPECT_EQ(omp_get_max_active_levels(), levels);
    }
    // Inside a parallel region each thread factorises its own copy and touches nothing global.
    omp_set_max_active_levels(1);
    int failures = 0;
#pragma omp parallel num_threads(2) reduction(+ : failures)
    {
        SparseCholesky llt;
        failures += llt.factorize(lower) == FactorStatus::Success ? 0 : 1;
        failures += omp_get_max_active_levels() == 1 ? 0 : 1;
    }
    EXPECT_EQ(failures, 0);
    EXPECT_EQ(omp_get_max_active_levels(), 1);
    // A parallel loop after all this still runs on more than one thread (if there are two).
    int threads = 0;
#pragma omp parallel num_threads(2)
    {
#pragma omp single
        threads = omp_get_num_threads();
    }
    EXPECT_EQ(threads, omp_get_num_procs() > 1 ? 2 : threads);
}

} // namespace
} // namespace lb
