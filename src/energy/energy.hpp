#pragma once
// One Energy interface for every term of the incremental potential.
//
// An energy is a sum over elements, each touching a fixed number K of vertices:
//   E(x) = Σ_e E_e(x_e),   x_e ∈ R^{3K} gathered from x (3N, xyz interleaved).
// Concrete energies implement only the three element-level functions (value,
// gradient, Hessian with fixed-size Eigen types) by deriving from
// ElementEnergy<K>; summation, gradient scatter and PSD projection live here,
// and sparse assembly lives in energy/hessian_assembler.hpp, written once.
// An energy whose element Hessian has a known eigenstructure may override the
// projection hook (ElementEnergy::local_projected_hessian) with something cheaper
// than the generic 3K×3K eigenvalue clamp (TetStVK does).
//
// Thread safety: all const member functions may be called concurrently.
#include <memory>
#include <string>
#include <vector>

#include "core/psd_projection.hpp"
#include "core/types.hpp"

namespace lb {

class Energy {
public:
    virtual ~Energy() = default;

    virtual std::string name() const = 0;
    virtual Index num_elements() const = 0;
    /// Number of vertices K per element.
    virtual int nodes_per_element() const = 0;
    /// Pointer to the K vertex indices of element e.
    virtual const int* element_nodes(Index e) const = 0;

    /// Element energy E_e at the global state x (3N).
    virtual double element_value(Index e, const VectorXd& x) const = 0;
    /// Writes ∂E_e/∂x_e (3K values) to g.
    virtual void element_gradient(Index e, const VectorXd& x, double* g) const = 0;
    /// E_e, with ∂E_e/∂x_e written to g, from one evaluation (what they share is computed
    /// once). Default: element_value then element_gradient.
    virtual double element_value_gradient(Index e, const VectorXd& x, double* g) const;
    /// Writes ∂²E_e/∂x_e² (3K×3K, column-major) to H, PSD-projected if asked.
    virtual void element_hessian(Index e, const VectorXd& x, bool project_psd, double* H) const = 0;
    /// True if the Hessian is identically zero (e.g. gravity): assembly skips it.
    virtual bool has_zero_hessian() const { return false; }

    /// E(x) = Σ_e E_e (OpenMP-parallel reduction).
    double value(const VectorXd& x) const;
    /// g += weight · ∇E(x).
    void add_gradient(const VectorXd& x, double weight, VectorXd& g) const;
    /// ∇E(x) (3N).
    VectorXd gradient(const VectorXd& x) const;
    /// Returns E(x) and adds weight · ∇E(x) to g, in one pass over the elements
    /// (element_value_gradient). Inside an OpenMP parallel region (the training losses
    /// parallelise over the samples of a batch) and for small meshes it runs serially,
    /// scattering as it goes, and allocates nothing. An energy may override it with the
    /// same serial pass and its element kernel inlined (InlinedElementEnergy).
    virtual double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const;
    /// Samples per column pass (add_value_gradient_columns): 8 doubles, one AVX-512 register.
    static constexpr int kColumnLanes = 8;
    /// True if the energy has add_value_gradient_columns (the element-lane energies: rods,
    /// shells, tets).
    virtual bool has_column_pass() const { return false; }
    /// add_value_gradient's serial pass for kColumnLanes samples at once, the SIMD lanes over
    /// the samples instead of over the elements (energy/element_lanes.hpp): X and G hold
    /// 3N × kColumnLanes numbers, row-major (coordinate r of sample l at r · kColumnLanes + l).
    /// Adds weight · ∇E of sample l to its column of G and E of sample l to values[l]: the same
    /// numbers as add_value_gradient on that sample, bit for bit. Throws Error if
    /// !has_column_pass().
    virtual void add_value_gradient_columns(const double* X, double weight, double* G, double* values) const;
    /// True where add_value_gradient runs its serial pass: inside a parallel region (even a
    /// one-thread one), with one thread available, or below kParallelElementThreshold elements.
    bool serial_value_gradient() const;
    /// Dense-free sparse Hessian over all 3N DOFs (full, both triangles); for
    /// tests and small problems. Newton uses HessianAssembler instead.
    SparseMatrixd hessian(const VectorXd& x, bool project_psd) const;
};

/// Base for energies whose elements have K vertices. Derived classes implement
/// local_value/local_gradient/local_hessian on the gathered element vector.
template <int K>
class ElementEnergy : public Energy {
public:
    static constexpr int kNodes = K;
    static constexpr int kDofs = 3 * K;
    using ElementVector = Eigen::Matrix<double, kDofs, 1>;
    using ElementMatrix = Eigen::Matrix<double, kDofs, kDofs>;
    // Row-major so element e's K nodes are contiguous; Eigen forbids RowMajor on a
    // single-column matrix, and for K = 1 column-major has the same layout.
    using Elements = Eigen::Matrix<int, Eigen::Dynamic, K, (K == 1 ? Eigen::ColMajor : Eigen::RowMajor)>;

    explicit ElementEnergy(Elements elements) : m_elements(std::move(elements)) { }

    Index num_elements() const final { return m_elements.rows(); }
    int nodes_per_element() const final { return K; }
    const int* element_nodes(Index e) const final { return m_elements.data() + e * K; }
    const Elements& elements() const { return m_elements; }

    ElementVector gather(Index e, const VectorXd& x) const
    {
        ElementVector xe;
        for (int a = 0; a < K; ++a) {
            xe.template segment<3>(3 * a) = x.template segment<3>(3 * Index(m_elements(e, a)));
        }
        return xe;
    }

    double element_value(Index e, const VectorXd& x) const final
    {
        return local_value(e, gather(e, x));
    }
    void element_gradient(Index e, const VectorXd& x, double* g) const final
    {
        Eigen::Map<ElementVector> out(g);
        out = local_gradient(e, gather(e, x));
    }
    double element_value_gradient(Index e, const VectorXd& x, double* g) const final
    {
        ElementVector ge;
        const double value = local_value_gradient(e, gather(e, x), ge);
        Eigen::Map<ElementVector> out(g);
        out = ge;
        return value;
    }
    void element_hessian(Index e, const VectorXd& x, bool project, double* H) const final
    {
        const ElementVector xe = gather(e, x);
        Eigen::Map<ElementMatrix> out(H);
        if (project) {
            out = local_projected_hessian(e, xe);
        } else {
            out = local_hessian(e, xe);
        }
    }

protected:
    virtual double local_value(Index e, const ElementVector& xe) const = 0;
    virtual ElementVector local_gradient(Index e, const ElementVector& xe) const = 0;
    virtual ElementMatrix local_hessian(Index e, const ElementVector& xe) const = 0;
    /// local_value, with local_gradient written to g; override when the two share work
    /// (the derivative tests check an override against both).
    virtual double local_value_gradient(Index e, const ElementVector& xe, ElementVector& g) const
    {
        g = local_gradient(e, xe);
        return local_value(e, xe);
    }
    /// A positive semi-definite stand-in for local_hessian, used by Newton's projected
    /// fallback. Contract: symmetric, PSD up to round-off, and equal to local_hessian
    /// whenever that is already PSD. The default clamps the eigenvalues of the 3K×3K
    /// element Hessian (its nearest PSD matrix in the Frobenius norm); an override may
    /// return a different PSD matrix if it is much cheaper (see TetStVK).
    virtual ElementMatrix local_projected_hessian(Index e, const ElementVector& xe) const
    {
        return project_psd(local_hessian(e, xe));
    }

private:
    Elements m_elements;
};

/// ElementEnergy<K> whose add_value_gradient runs the serial pass with Derived's
/// local_value_gradient called directly (inlined, no virtual call per element): the
/// training losses evaluate value and gradient of every sample this way. Derived is the
/// final energy class and names this base a friend, so its protected kernel can be called
/// by its qualified name:
///   class RodStretching final : public InlinedElementEnergy<RodStretching, 2> {
///       friend class InlinedElementEnergy<RodStretching, 2>; ...
template <typename Derived, int K>
class InlinedElementEnergy : public ElementEnergy<K> {
public:
    using ElementEnergy<K>::ElementEnergy;
    using typename ElementEnergy<K>::ElementVector;

    /// The serial pass with Derived::local_value_gradient called directly; the parallel pass
    /// is Energy's.
    double add_value_gradient(const VectorXd& x, double weight, VectorXd& g) const override
    {
        if (!this->serial_value_gradient()) return Energy::add_value_gradient(x, weight, g);
        const Derived& self = static_cast<const Derived&>(*this);
        double sum = 0.0;
        ElementVector ge;
        const Index n = this->num_elements();
        for (Index e = 0; e < n; ++e) {
            sum += self.Derived::local_value_gradient(e, this->gather(e, x), ge);  // qualified: not virtual
            const int* nodes = this->element_nodes(e);
            for (int a = 0; a < K; ++a) {
                g.template segment<3>(3 * Index(nodes[a])) += weight * ge.template segment<3>(3 * a);
            }
        }
        return sum;
    }
};

/// A weighted sum of energies, E = Σ_k w_k E_k: the incremental potential of
/// implicit Euler (inertia + elastic + gravity [+ Dirichlet penalty]).
struct WeightedEnergy {
    double weight = 1.0;
    std::shared_ptr<const Energy> energy;
};

class EnergySum {
public:
    EnergySum() = default;
    explicit EnergySum(std::vector<WeightedEnergy> terms) : m_terms(std::move(terms)) { }
    void add(std::shared_ptr<const Energy> energy, double weight = 1.0)
    {
        m_terms.push_back({weight, std::move(energy)});
    }
    const std::vector<WeightedEnergy>& terms() const { return m_terms; }

    double value(const VectorXd& x) const;
    VectorXd gradient(const VectorXd& x) const;
    /// gradient(x) written to g (resized; no allocation once it has the size).
    void gradient(const VectorXd& x, VectorXd& g) const;
    /// Σ_k w_k E_k(x), with its gradient written to g (resized): one pass per term.
    double value_gradient(const VectorXd& x, VectorXd& g) const;
    /// Per-term values, in the order of terms() (for logging and metrics).
    std::vector<double> term_values(const VectorXd& x) const;

private:
    std::vector<WeightedEnergy> m_terms;
};

} // namespace lb
