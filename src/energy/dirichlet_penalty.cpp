#include "energy/dirichlet_penalty.hpp"

#include <sstream>

#include "core/error.hpp"
#include "energy/element_input.hpp"

namespace lb {
namespace {
ElementEnergy<1>::Elements index_elements(const std::vector<int>& indices)
{
    ElementEnergy<1>::Elements elements(Index(indices.size()), 1);
    for (size_t b = 0; b < indices.size(); ++b) {
        if (indices[b] < 0) {
            std::ostringstream msg;
            msg << "DirichletPenalty: boundary index " << b << " is negative (" << indices[b] << ")";
            throw Error(msg.str());
        }
        elements(Index(b), 0) = indices[b];
    }
    return elements;
}
} // namespace

DirichletPenalty::DirichletPenalty(std::vector<int> indices, double weight)
    : ElementEnergy<1>(index_elements(indices)),
      m_indices(std::move(indices)),
      m_weight(weight),
      m_targets(MatrixX3d::Zero(Index(m_indices.size()), 3))
{
    detail::require_positive(weight, "DirichletPenalty", "weight");
}

void DirichletPenalty::set_targets(const Eigen::Ref<const MatrixX3d>& targets)
{
    if (targets.rows() != Index(m_indices.size())) {
        std::ostringstream msg;
        msg << "DirichletPenalty::set_targets: expected " << m_indices.size() << " target rows, got "
            << targets.rows();
        throw Error(msg.str());
    }
    m_targets = targets;
}

double DirichletPenalty::add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const
{
    double sum = 0.0;
    for (size_t b = 0; b < m_indices.size(); ++b) {
        const Index i = 3 * Index(m_indices[b]);
        const Vector3d d = x.segment<3>(i) - m_targets.row(Index(b)).transpose();
        sum += d.squaredNorm();
        g.segment<3>(i) += (2.0 * weight * m_weight) * d;
    }
    return m_weight * sum;
}

double DirichletPenalty::local_value(Index b, const ElementVector& xe) const
{
    return m_weight * (xe - m_targets.row(b).transpose()).squaredNorm();
}

DirichletPenalty::ElementVector DirichletPenalty::local_gradient(Index b, const ElementVector& xe) const
{
    return 2.0 * m_weight * (xe - m_targets.row(b).transpose());
}

DirichletPenalty::ElementMatrix DirichletPenalty::local_hessian(Index, const ElementVector&) const
{
    return 2.0 * m_weight * ElementMatrix::Identity();
}

} // namespace lb
