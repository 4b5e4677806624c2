#include "solver/sparse_cholesky.hpp"

#include <Eigen/CholmodSupport>

#include "core/error.hpp"

namespace lb {

struct SparseCholesky::Impl {
    Eigen::CholmodDecomposition<SparseMatrixd, Eigen::Lower> llt;
};

SparseCholesky::SparseCholesky() : m_impl(std::make_unique<Impl>())
{
    // LLᵀ, supernodal or simplicial as CHOLMOD's flop-count heuristic decides
    // (supernodal for every scene we ship; simplicial for very sparse factors).
    m_impl->llt.setMode(Eigen::CholmodAuto);
    // Failures are reported through FactorStatus; CHOLMOD's own stderr warnings
    // ("matrix not positive definite") would only repeat them.
    m_impl->llt.cholmod().print = 0;
}
SparseCholesky::~SparseCholesky() = default;

void SparseCholesky::analyze(const SparseMatrixd& lower)
{
    m_impl->llt.analyzePattern(lower);
    if (m_impl->llt.info() != Eigen::Success) {
        throw NumericalError("CHOLMOD symbolic analysis failed");
    }
    m_analyzed = true;
}

FactorStatus SparseCholesky::factorize(const SparseMatrixd& lower)
{
    if (!m_analyzed) analyze(lower);
    const double* v = lower.valuePtr();
    for (Index i = 0; i < lower.nonZeros(); ++i) {
        if (!std::isfinite(v[i])) {
            m_message = "non-finite entry in the Hessian";
            return FactorStatus::Fatal;
        }
    }
    m_impl->llt.factorize(lower);
    switch (m_impl->llt.info()) {
    case Eigen::Success:
        m_message.clear();
        return FactorStatus::Success;
    case Eigen::NumericalIssue:
        m_message = "matrix not positive definite";
        return FactorStatus::NotPositiveDefinite;
    default:
        m_message = "CHOLMOD factorisation failed";
        return FactorStatus::Fatal;
    }
}

VectorXd SparseCholesky::solve(const VectorXd& b) const { return m_impl->llt.solve(b); }

} // namespace lb
