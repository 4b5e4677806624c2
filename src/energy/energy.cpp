#include "energy/energy.hpp"

#include "core/error.hpp"
#include "core/parallel.hpp"

#include <omp.h>

#include <vector>

namespace lb {

double Energy::value(const VectorXd& x) const
{
    double sum = 0.0;
    const Index n = num_elements();
    if (serial_value_gradient()) {
        for (Index e = 0; e < n; ++e) sum += element_value(e, x);
        return sum;
    }
    // Element values in parallel, summed serially in element order: the one-thread sum,
    // whatever the thread count (an OpenMP reduction's partial sums follow the threads).
    std::vector<double> values(static_cast<size_t>(n));
#pragma omp parallel for schedule(static)
    for (Index e = 0; e < n; ++e) values[size_t(e)] = element_value(e, x);
    for (Index e = 0; e < n; ++e) sum += values[size_t(e)];
    return sum;
}

namespace {
/// The calling thread's element buffer of at least `size` doubles: kept (and only grown)
/// between calls, so the full-space Newton step's gradients allocate nothing once the
/// largest energy has been evaluated on this thread (tests/sim/test_step_allocations.cpp).
double* element_buffer(int which, size_t size)
{
    thread_local std::vector<double> buffers[2];
    std::vector<double>& b = buffers[which];
    if (b.size() < size) b.resize(size);
    return b.data();
}
} // namespace

void Energy::add_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    const Index n = num_elements();
    const int k = nodes_per_element();
    const int dofs = 3 * k;
    // Element gradients are computed in parallel, then scattered serially
    // (elements share vertices, so a parallel scatter would race).
    double* local = element_buffer(0, static_cast<size_t>(n * dofs));
    // parallel_for: below the threshold or on one thread no OpenMP region is opened
    // (libgomp allocates a team for each).
    parallel_for(n, n >= kParallelElementThreshold, [&](std::ptrdiff_t e) { element_gradient(e, x, local + e * dofs); });
    for (Index e = 0; e < n; ++e) {
        const int* nodes = element_nodes(e);
        const double* ge = local + e * dofs;
        for (int a = 0; a < k; ++a) {
            g.segment<3>(3 * Index(nodes[a])) += weight * Eigen::Map<const Vector3d>(ge + 3 * a);
        }
    }
}

double Energy::element_value_gradient(Index e, const VectorXd& x, double* g) const
{
    element_gradient(e, x, g);
    return element_value(e, x);
}

double Energy::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    const Index n = num_elements();
    const int k = nodes_per_element();
    const int dofs = 3 * k;
    auto scatter = [&](Index e, const double* ge) {
        const int* nodes = element_nodes(e);
        for (int a = 0; a < k; ++a) g.segment<3>(3 * Index(nodes[a])) += weight * Eigen::Map<const Vector3d>(ge + 3 * a);
    };
    double sum = 0.0;
    if (serial_value_gradient()) {
        constexpr int kMaxDofs = 12;
        Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDofs, 1> ge(dofs);
        for (Index e = 0; e < n; ++e) {
            sum += element_value_gradient(e, x, ge.data());
            scatter(e, ge.data());
        }
        return sum;
    }
    // As add_gradient: element gradients in parallel, scattered serially; the values summed
    // serially too, in element order (as value()). This branch (top level, large meshes,
    // several threads) has no caller in the pipeline, which calls it inside parallel regions;
    // it gives the serial pass's numbers for the cloth's terms, not bit for bit for the
    // lane-blocked tetrahedra (TetStVK), whose serial pass runs its own element order.
    double* local = element_buffer(0, static_cast<size_t>(n * dofs));
    double* values = element_buffer(1, static_cast<size_t>(n));
#pragma omp parallel for schedule(static)
    for (Index e = 0; e < n; ++e) {
        values[e] = element_value_gradient(e, x, local + e * dofs);
    }
    for (Index e = 0; e < n; ++e) {
        sum += values[e];
        scatter(e, local + e * dofs);
    }
    return sum;
}

void Energy::add_value_gradient_columns(const double*, double, double*, double*) const
{
    throw Error("Energy '" + name() + "' has no column pass (has_column_pass() is false)");
}

bool Energy::serial_value_gradient() const
{
    // omp_get_level, not omp_in_parallel: a batch loop run on one thread (`-j 1`) is an
    // inactive region, and a one-thread "parallel" pass would allocate and fill the
    // element buffer for nothing, every sample.
    return omp_get_level() > 0 || omp_get_max_threads() == 1 || num_elements() < kParallelElementThreshold;
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
    VectorXd g;
    gradient(x, g);
    return g;
}

void EnergySum::gradient(const VectorXd& x, VectorXd& g) const
{
    g.setZero(x.size());
    for (const auto& term : m_terms) term.energy->add_gradient(x, term.weight, g);
}

double EnergySum::value_gradient(const VectorXd& x, VectorXd& g) const
{
    g.setZero(x.size());
    double sum = 0.0;
    for (const auto& term : m_terms) sum += term.weight * term.energy->add_value_gradient(x, term.weight, g);
    return sum;
}

std::vector<double> EnergySum::term_values(const VectorXd& x) const
{
    std::vector<double> values;
    for (const auto& term : m_terms) values.push_back(term.weight * term.energy->value(x));
    return values;
}

} // namespace lb
