#include "energy/energy.hpp"

#include "core/parallel.hpp"

#include <vector>

namespace lb {

double Energy::value(const VectorXd& x) const
{
    double sum = 0.0;
    const Index n = num_elements();
#pragma omp parallel for reduction(+ : sum) schedule(static) if (n >= kParallelElementThreshold)
    for (Index e = 0; e < n; ++e) {
        sum += element_value(e, x);
    }
    return sum;
}

void Energy::add_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    const Index n = num_elements();
    const int k = nodes_per_element();
    const int dofs = 3 * k;
    // Element gradients are computed in parallel, then scattered serially
    // (elements share vertices, so a parallel scatter would race).
    std::vector<double> local(static_cast<size_t>(n * dofs));
#pragma omp parallel for schedule(static) if (n >= kParallelElementThreshold)
    for (Index e = 0; e < n; ++e) {
        element_gradient(e, x, local.data() + e * dofs);
    }
    for (Index e = 0; e < n; ++e) {
        const int* nodes = element_nodes(e);
        const double* ge = local.data() + e * dofs;
        for (int a = 0; a < k; ++a) {
            g.segment<3>(3 * Index(nodes[a])) += weight * Eigen::Map<const Vector3d>(ge + 3 * a);
        }
    }
}

VectorXd Energy::gradient(const VectorXd& x) const
{
    VectorXd g = VectorXd::Zero(x.size());
    add_gradient(x, 1.0, g);
    return g;
}

SparseMatrixd Energy::hessian(const VectorXd& x, bool project_psd) const
{
    const int k = nodes_per_element();
    const int dofs = 3 * k;
    std::vector<Eigen::Triplet<double>> triplets;
    std::vector<double> h(static_cast<size_t>(dofs * dofs));
    for (Index e = 0; e < num_elements(); ++e) {
        element_hessian(e, x, project_psd, h.data());
        const int* nodes = element_nodes(e);
        for (int b = 0; b < dofs; ++b) {
            for (int a = 0; a < dofs; ++a) {
                triplets.emplace_back(3 * nodes[a / 3] + a % 3, 3 * nodes[b / 3] + b % 3,
                                      h[size_t(a + b * dofs)]);
            }
        }
    }
    SparseMatrixd H(x.size(), x.size());
    H.setFromTriplets(triplets.begin(), triplets.end());
    return H;
}

double EnergySum::value(const VectorXd& x) const
{
    double sum = 0.0;
    for (const auto& term : m_terms) sum += term.weight * term.energy->value(x);
    return sum;
}

VectorXd EnergySum::gradient(const VectorXd& x) const
{
    VectorXd g = VectorXd::Zero(x.size());
    for (const auto& term : m_terms) term.energy->add_gradient(x, term.weight, g);
    return g;
}

std::vector<double> EnergySum::term_values(const VectorXd& x) const
{
    std::vector<double> values;
    for (const auto& term : m_terms) values.push_back(term.weight * term.energy->value(x));
    return values;
}

} // namespace lb
