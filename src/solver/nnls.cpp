#include "solver/nnls.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <vector>

namespace lb {

namespace {

/// The unconstrained minimiser on the passive set: G_PP s_P = c_P, s = 0 elsewhere.
VectorXd passive_solution(const Eigen::Ref<const MatrixXd>& G, const Eigen::Ref<const VectorXd>& c,
                          const std::vector<Index>& passive)
{
    const Index k = Index(passive.size());
    MatrixXd Gp(k, k);
    VectorXd cp(k);
    for (Index a = 0; a < k; ++a) {
        cp[a] = c[passive[size_t(a)]];
        for (Index b = 0; b < k; ++b) Gp(a, b) = G(passive[size_t(a)], passive[size_t(b)]);
    }
    const VectorXd sp = Gp.ldlt().solve(cp);
    VectorXd s = VectorXd::Zero(G.rows());
    for (Index a = 0; a < k; ++a) s[passive[size_t(a)]] = sp[a];
    return s;
}

} // namespace

NnlsResult nnls_gram(const Eigen::Ref<const MatrixXd>& G, const Eigen::Ref<const VectorXd>& c,
                     const NnlsOptions& options)
{
    const Index n = c.size();
    NnlsResult result;
    result.w = VectorXd::Zero(n);
    if (G.rows() != n || G.cols() != n) {
        result.message = "G must be n × n with n = size of c";
        return result;
    }
    if (n == 0) {
        result.converged = true;
        return result;
    }
    const int max_iterations = options.max_iterations > 0 ? options.max_iterations : int(3 * n);
    const double tol = options.tolerance * std::max(1.0, c.lpNorm<Eigen::Infinity>());
    std::vector<bool> in_passive(size_t(n), false);
    std::vector<Index> passive;
    VectorXd& w = result.w;
    VectorXd r = c;  // Aᵀ(b − A w) at w = 0
    while (true) {
        // The most violated Kuhn–Tucker condition among the variables held at zero.
        Index t = -1;
        double best = tol;
        for (Index j = 0; j < n; ++j)
            if (!in_passive[size_t(j)] && r[j] > best) {
                best = r[j];
                t = j;
            }
        if (t < 0) {
            result.converged = true;
            return result;
        }
        if (result.iterations >= max_iterations) {
            result.message = "Lawson–Hanson: " + std::to_string(max_iterations) + " outer iterations without meeting "
                             "the Kuhn–Tucker conditions";
            return result;
        }
        ++result.iterations;
        in_passive[size_t(t)] = true;
        passive.push_back(t);
        for (int inner = 0;; ++inner) {
            const VectorXd s = passive_solution(G, c, passive);
            bool feasible = s.allFinite();
            for (Index j : passive) feasible = feasible && s[j] > 0.0;
            if (feasible) {
                w = s;
                break;
            }
            if (!s.allFinite() || inner > 3 * n) {
                // A singular passive block (a column dependent on the others): drop the
                // variable just added and stop its entry; r_t ≤ 0 afterwards keeps it out.
                in_passive[size_t(t)] = false;
                passive.erase(std::remove(passive.begin(), passive.end(), t), passive.end());
                result.message = "Lawson–Hanson: singular least-squares sub-problem";
                return result;
            }
            // Interpolate towards s until the first passive variable hits zero.
            double alpha = 1.0;
            for (Index j : passive)
                if (s[j] <= 0.0) alpha = std::min(alpha, w[j] / (w[j] - s[j]));
            w += alpha * (s - w);
            std::vector<Index> kept;
            for (Index j : passive) {
                if (w[j] <= 0.0 || (s[j] <= 0.0 && w[j] <= 1e-14 * std::max(1.0, w.lpNorm<Eigen::Infinity>()))) {
                    w[j] = 0.0;
                    in_passive[size_t(j)] = false;
                } else {
                    kept.push_back(j);
                }
            }
            passive.swap(kept);
            if (passive.empty()) break;
        }
        r = c - G * w;
    }
}

NnlsResult nnls(const Eigen::Ref<const MatrixXd>& A, const Eigen::Ref<const VectorXd>& b, const NnlsOptions& options)
{
    NnlsResult result;
    if (A.rows() != b.size()) {
        result.w = VectorXd::Zero(A.cols());
        result.message = "A has " + std::to_string(A.rows()) + " rows, b " + std::to_string(b.size()) + " entries";
        return result;
    }
    const MatrixXd G = A.transpose() * A;
    const VectorXd c = A.transpose() * b;
    return nnls_gram(G, c, options);
}

} // namespace lb
