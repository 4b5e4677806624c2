#pragma once
// The problem side of the problem/solver split (as in Ceres and PolyFEM): a smooth
// f: ℝⁿ → ℝ with its gradient and, optionally, its Hessian (dense or sparse),
// minimised by minimize_newton (solver/newton.hpp, needs a Hessian) or
// minimize_lbfgs (solver/lbfgs.hpp, gradient only). The convergence scales (force,
// length) are part of the solver options, set by the caller from the problem.
//
// Implementations may reuse internal buffers (e.g. the full-space positions the
// unknowns are scattered into), so the evaluation methods are not const and one
// Objective must not be evaluated from two threads at once.
#include <stdexcept>

#include "core/types.hpp"

namespace lb {

enum class HessianKind { None, Dense, Sparse };

class Objective {
public:
    virtual ~Objective() = default;

    /// n, the number of unknowns.
    virtual Index dimension() const = 0;

    /// f(x) for x of size n. May be +inf or NaN where f is undefined (an inverted
    /// element): the line searches reject such trial points.
    virtual double value(const Eigen::Ref<const VectorXd>& x) = 0;

    /// ∇f(x) written into g (size n, already sized by the caller).
    virtual void gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g) = 0;

    /// f(x) and ∇f(x) together (what L-BFGS asks for); override when the two share work.
    virtual double value_and_gradient(const Eigen::Ref<const VectorXd>& x, Eigen::Ref<VectorXd> g)
    {
        gradient(x, g);
        return value(x);
    }

    /// Which of dense_hessian / sparse_hessian is implemented.
    virtual HessianKind hessian_kind() const { return HessianKind::None; }

    /// ∇²f(x) as a dense n × n symmetric matrix (H is resized). With `project_psd`, a
    /// positive semi-definite approximation instead (e.g. element Hessians with their
    /// negative eigenvalues clamped): Newton asks for it only when the exact Hessian
    /// does not factorise or gives no descent direction.
    virtual void dense_hessian(const Eigen::Ref<const VectorXd>& x, bool project_psd, MatrixXd& H)
    {
        (void)x, (void)project_psd, (void)H;
        throw std::logic_error("Objective::dense_hessian: this objective has no dense Hessian");
    }

    /// Lower triangle (row ≥ column, sorted, the diagonal stored in every column) of
    /// ∇²f(x) (or its PSD projection, as above), n × n. The sparsity pattern must be the
    /// same on every call so that the symbolic Cholesky analysis is done once. The
    /// matrix is owned by the objective; the minimiser may change its values in place
    /// (a diagonal shift) until the next call.
    virtual SparseMatrixd& sparse_hessian(const Eigen::Ref<const VectorXd>& x, bool project_psd)
    {
        (void)x, (void)project_psd;
        throw std::logic_error("Objective::sparse_hessian: this objective has no sparse Hessian");
    }

    /// The largest displacement (in the length unit of the options' length_scale) that
    /// a step dx of the unknowns causes: ||dx||_∞ when the unknowns are positions; a
    /// subspace objective measures the positions it decodes to (||J dx||_∞).
    virtual double step_length(const Eigen::Ref<const VectorXd>& dx) { return dx.lpNorm<Eigen::Infinity>(); }
};

} // namespace lb
