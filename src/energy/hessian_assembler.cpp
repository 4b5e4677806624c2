#include "energy/hessian_assembler.hpp"

#include "core/parallel.hpp"

#include <cassert>

#include "core/error.hpp"

namespace lb {
namespace {
// Calls f(term, element, local_index, row, col) for every stored (lower) entry.
template <typename F>
void for_each_entry(const VectorXi& dof_to_unknown, const Energy& energy, F&& f)
{
    const int dofs = 3 * energy.nodes_per_element();
    for (Index e = 0; e < energy.num_elements(); ++e) {
        const int* nodes = energy.element_nodes(e);
        for (int b = 0; b < dofs; ++b) {
            const int col = dof_to_unknown[3 * nodes[b / 3] + b % 3];
            for (int a = 0; a < dofs; ++a) {
                const int row = dof_to_unknown[3 * nodes[a / 3] + a % 3];
                f(e, a + b * dofs, row, col);
            }
        }
    }
}
} // namespace

HessianAssembler::HessianAssembler(const VectorXi& dof_to_unknown, const EnergySum& energies)
    : m_dof_to_unknown(dof_to_unknown)
{
    m_num_unknowns = 0;
    for (Index i = 0; i < dof_to_unknown.size(); ++i) {
        if (dof_to_unknown[i] >= 0) ++m_num_unknowns;
    }
    m_unknown_to_dof.setConstant(m_num_unknowns, -1);
    for (Index i = 0; i < dof_to_unknown.size(); ++i) {
        if (dof_to_unknown[i] >= 0) m_unknown_to_dof[dof_to_unknown[i]] = int(i);
    }

    // Pattern: union of all element blocks (+ the diagonal, so regularisation
    // μI always has a slot).
    std::vector<Eigen::Triplet<double>> triplets;
    for (Index i = 0; i < m_num_unknowns; ++i) triplets.emplace_back(i, i, 1.0);
    for (const auto& term : energies.terms()) {
        if (term.energy->has_zero_hessian()) continue;
        for_each_entry(m_dof_to_unknown, *term.energy, [&](Index, int, int row, int col) {
            if (row >= 0 && col >= 0 && row >= col) triplets.emplace_back(row, col, 1.0);
        });
    }
    m_matrix.resize(m_num_unknowns, m_num_unknowns);
    m_matrix.setFromTriplets(triplets.begin(), triplets.end());
    m_matrix.makeCompressed();

    // Scatter maps: position of each (row, col) in the compressed value array.
    const auto* outer = m_matrix.outerIndexPtr();
    const auto* inner = m_matrix.innerIndexPtr();
    auto find = [&](int row, int col) {
        const auto* begin = inner + outer[col];
        const auto* end = inner + outer[col + 1];
        const auto* it = std::lower_bound(begin, end, row);
        assert(it != end && *it == row);
        return int(it - inner);
    };
    for (const auto& term : energies.terms()) {
        std::vector<int> scatter;
        if (!term.energy->has_zero_hessian()) {
            const int dofs = 3 * term.energy->nodes_per_element();
            scatter.assign(size_t(term.energy->num_elements() * dofs * dofs), -1);
            for_each_entry(m_dof_to_unknown, *term.energy, [&](Index e, int local, int row, int col) {
                if (row >= 0 && col >= 0 && row >= col) {
                    scatter[size_t(e * dofs * dofs + local)] = find(row, col);
                }
            });
        }
        m_scatter.push_back(std::move(scatter));
    }
    m_buffers.resize(m_scatter.size());
}

void HessianAssembler::assemble(const EnergySum& energies, const VectorXd& x, bool project_psd)
{
    if (energies.terms().size() != m_scatter.size()) {
        throw Error("HessianAssembler::assemble: the energy terms differ from construction");
    }
    double* values = m_matrix.valuePtr();
    std::fill(values, values + m_matrix.nonZeros(), 0.0);
    for (size_t k = 0; k < m_scatter.size(); ++k) {
        const auto& term = energies.terms()[k];
        if (term.energy->has_zero_hessian()) continue;
        const Energy& energy = *term.energy;
        const Index n = energy.num_elements();
        const int dofs = 3 * energy.nodes_per_element();
        const size_t block = size_t(dofs * dofs);
        std::vector<double>& buffer = m_buffers[k];
        buffer.resize(size_t(n) * block);
        // parallel_for: below the threshold or on one thread no OpenMP region is opened
        // (libgomp allocates a team for each).
        double* out = buffer.data();
        parallel_for(n, n >= kParallelElementThreshold,
                     [&](std::ptrdiff_t e) { energy.element_hessian(e, x, project_psd, out + size_t(e) * block); });
        const std::vector<int>& scatter = m_scatter[k];
        const double w = term.weight;
        for (size_t i = 0; i < scatter.size(); ++i) {
            if (scatter[i] >= 0) values[scatter[i]] += w * buffer[i];
        }
    }
}

VectorXd HessianAssembler::restrict(const VectorXd& full) const
{
    VectorXd reduced;
    restrict(full, reduced);
    return reduced;
}

void HessianAssembler::restrict(const VectorXd& full, VectorXd& reduced) const
{
    reduced.resize(m_num_unknowns);
    for (Index i = 0; i < m_num_unknowns; ++i) reduced[i] = full[m_unknown_to_dof[i]];
}

void HessianAssembler::add_prolonged(const VectorXd& reduced, VectorXd& full) const
{
    for (Index i = 0; i < m_num_unknowns; ++i) full[m_unknown_to_dof[i]] += reduced[i];
}

} // namespace lb
