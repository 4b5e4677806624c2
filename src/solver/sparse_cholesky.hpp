#pragma once
// Sparse Cholesky (CHOLMOD LLᵀ through Eigen's CholmodSupport; supernodal for
// large factors, simplicial for small ones)
// behind a small wrapper: analyse the pattern once, factorise each Newton
// iteration, report a status instead of throwing.
#include <memory>
#include <string>

#include "core/types.hpp"

namespace lb {

enum class FactorStatus {
    Success,
    /// Not positive definite: recoverable by regularisation (add μI, retry).
    NotPositiveDefinite,
    /// Anything else (out of memory, NaN entries): the solve cannot continue.
    Fatal,
};

class SparseCholesky {
public:
    SparseCholesky();
    ~SparseCholesky();
    SparseCholesky(const SparseCholesky&) = delete;
    SparseCholesky& operator=(const SparseCholesky&) = delete;

    /// Symbolic analysis of the lower-triangular pattern; call once per pattern.
    void analyze(const SparseMatrixd& lower);
    /// Numeric factorisation (values may change, pattern may not).
    FactorStatus factorize(const SparseMatrixd& lower);
    /// Solve A x = b with the last successful factorisation.
    VectorXd solve(const VectorXd& b) const;
    /// solve(b) written to x (resized): CHOLMOD's solution and workspace are kept between
    /// calls, so a solve of the same size allocates nothing.
    void solve(const VectorXd& b, VectorXd& x);
    const std::string& message() const { return m_message; }
    /// CHOLMOD's figures for the analysed pattern (0 before analyze()): the factor's
    /// non-zeros and the floating-point operations of one numeric factorisation.
    double factor_nonzeros() const;
    double factorization_flops() const;
    bool analyzed() const { return m_analyzed; }

private:
    struct Impl;
    std::unique_ptr<Impl> m_impl;
    bool m_analyzed = false;
    std::string m_message;
};

} // namespace lb
