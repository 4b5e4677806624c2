#pragma once
// Non-negative least squares, min_w ||A w − b||₂ subject to w ≥ 0, by the active-set
// algorithm of Lawson & Hanson (Solving Least Squares Problems, 1974, ch. 23),
// written here from the algorithm's description:
//
//   P = ∅ (passive set, free variables), w = 0, r = Aᵀ(b − A w) (the negative gradient)
//   outer: while some j ∉ P has r_j > tolerance:
//       move argmax_{j∉P} r_j into P
//       inner: s = least-squares solution on the columns in P (s_j = 0 off P)
//              if every s_j > 0 on P: w = s, leave the inner loop
//              else step from w towards s until the first variable reaches 0
//                   (α = min_{j∈P, s_j ≤ 0} w_j / (w_j − s_j)), w += α (s − w),
//                   and move the variables that reached 0 out of P
//       r = Aᵀ(b − A w)
//
// The least-squares sub-problems are solved on the normal equations (AᵀA)_PP s_P =
// (Aᵀb)_P with an LDLᵀ factorisation, so the solver works from the Gram matrix
// G = AᵀA and c = Aᵀb alone: callers that grow A one column at a time (the greedy
// cubature of An et al. 2008) keep G up to date in O(rows · columns) per column
// instead of re-factorising A. (Squaring the condition number is harmless at the
// accuracy cubature weights need; nnls() on A itself uses the same path.)
#include <string>

#include "core/types.hpp"

namespace lb {

struct NnlsOptions {
    /// Outer iterations (variables made free) before giving up; 0: 3 · columns.
    int max_iterations = 0;
    /// A variable outside P enters only if its r_j exceeds tolerance · max(1, ||c||_∞).
    double tolerance = 1e-12;
};

struct NnlsResult {
    VectorXd w;               ///< the solution (≥ 0), size n
    bool converged = false;   ///< the Kuhn–Tucker conditions hold to the tolerance
    int iterations = 0;       ///< outer iterations
    std::string message;      ///< why it stopped when not converged
};

/// Lawson–Hanson on the Gram form: min_w ½ wᵀ G w − cᵀ w, w ≥ 0, G = AᵀA (n × n, symmetric
/// positive semi-definite), c = Aᵀb (n). Never throws on non-convergence.
NnlsResult nnls_gram(const Eigen::Ref<const MatrixXd>& G, const Eigen::Ref<const VectorXd>& c,
                     const NnlsOptions& options = {});

/// min_w ||A w − b||₂, w ≥ 0.   @param A  m × n   @param b  m
NnlsResult nnls(const Eigen::Ref<const MatrixXd>& A, const Eigen::Ref<const VectorXd>& b,
                const NnlsOptions& options = {});

} // namespace lb
