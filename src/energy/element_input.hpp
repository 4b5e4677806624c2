#pragma once
// Validation of the inputs every element energy receives at construction
// (element index arrays, material parameters). Bad input is a boundary error:
// it throws lb::Error with a message naming the energy and the offending value.
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/types.hpp"
#include "energy/energy.hpp"

namespace lb::detail {

/// Copy an E×K index array into the element storage of ElementEnergy<K>, checking the
/// column count and that every index lies in [0, num_vertices).
template <int K>
typename ElementEnergy<K>::Elements checked_elements(const Eigen::Ref<const MatrixXi>& elements,
                                                     Index num_vertices, const std::string& who)
{
    if (elements.cols() != K) {
        std::ostringstream msg;
        msg << who << ": expected " << K << " vertex indices per element, got a matrix with "
            << elements.cols() << " columns";
        throw Error(msg.str());
    }
    for (Index e = 0; e < elements.rows(); ++e) {
        for (int a = 0; a < K; ++a) {
            const int v = elements(e, a);
            if (v < 0 || v >= num_vertices) {
                std::ostringstream msg;
                msg << who << ": element " << e << " references vertex " << v << ", but there are "
                    << num_vertices << " vertices";
                throw Error(msg.str());
            }
        }
    }
    typename ElementEnergy<K>::Elements out(elements.rows(), K);
    for (Index e = 0; e < elements.rows(); ++e) {
        for (int a = 0; a < K; ++a) out(e, a) = elements(e, a);
    }
    return out;
}

/// Elements 0, 1, …, n−1 of one vertex each (per-vertex energies: inertia, gravity).
inline ElementEnergy<1>::Elements vertex_elements(Index n)
{
    ElementEnergy<1>::Elements elements(n, 1);
    for (Index i = 0; i < n; ++i) elements(i, 0) = int(i);
    return elements;
}

/// Throw unless value > 0 (Young's modulus, radius, thickness, dt...).
inline void require_positive(double value, const std::string& who, const std::string& what)
{
    if (!(value > 0.0)) {
        std::ostringstream msg;
        msg << who << ": " << what << " must be positive, got " << value;
        throw Error(msg.str());
    }
}

/// Throw unless −1 < ν < 0.5 (the range in which the Lamé parameters are finite and the
/// material is stable).
inline void require_poisson(double poisson, const std::string& who)
{
    if (!(poisson > -1.0 && poisson < 0.5)) {
        std::ostringstream msg;
        msg << who << ": Poisson ratio must lie in (-1, 0.5), got " << poisson;
        throw Error(msg.str());
    }
}

} // namespace lb::detail
