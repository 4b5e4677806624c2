#include "baselines/fulton_cubature/cubature.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "baselines/fulton_cubature/pca_split_decoder.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/rng.hpp"
#include "core/timer.hpp"
#include "io/hdf5.hpp"
#include "solver/nnls.hpp"

namespace lb {

namespace {

constexpr const char* kFormat = "latentbench.cubature/1";
/// Largest element stencil (hinges: 4 vertices; tets: 4; bending triples: 3).
constexpr int kMaxNodes = 8;

/// Global element numbering over the elastic terms: element g is (term, g − first[term]).
struct ElementIndex {
    std::vector<Index> first;  ///< first global index of each term, plus the total at the end

    explicit ElementIndex(const PhysicsModel& model)
    {
        first.push_back(0);
        for (const auto& term : model.elastic_terms()) first.push_back(first.back() + term->num_elements());
    }
    Index total() const { return first.back(); }
    std::pair<int, Index> locate(Index g) const
    {
        const auto it = std::upper_bound(first.begin(), first.end(), g);
        const int term = int(it - first.begin()) - 1;
        return {term, g - first[size_t(term)]};
    }
};

/// The reduced-force system of a set of poses: b and the columns a_e on demand.
class ForceSystem {
public:
    ForceSystem(const PhysicsModel& model, const PcaSplitDecoder& decoder, const MatrixXd& poses)
        : m_model(model), m_U(decoder.basis()), m_d(decoder.pca_dim())
    {
        std::vector<VectorXd> forces;
        double largest = 0.0;
        for (Index p = 0; p < poses.cols(); ++p) {
            VectorXd x = poses.col(p);
            VectorXd grad = VectorXd::Zero(x.size());
            for (const auto& term : model.elastic_terms()) term->add_gradient(x, 1.0, grad);
            VectorXd f = m_U.transpose() * grad;
            largest = std::max(largest, f.norm());
            m_poses.push_back(std::move(x));
            forces.push_back(std::move(f));
        }
        std::vector<VectorXd> kept_poses;
        for (size_t p = 0; p < forces.size(); ++p) {
            const double n = forces[p].norm();
            if (!(n > 1e-12 * largest) || !std::isfinite(n)) continue;
            kept_poses.push_back(std::move(m_poses[p]));
            m_inv_norms.push_back(1.0 / n);
            m_b.conservativeResize(m_b.size() + m_d);
            m_b.tail(m_d) = forces[p] / n;
        }
        m_poses.swap(kept_poses);
    }

    Index num_poses() const { return Index(m_poses.size()); }
    const VectorXd& b() const { return m_b; }

    /// a_e (T·d) for element (term, e).
    void column(int term, Index e, Eigen::Ref<VectorXd> a) const
    {
        const Energy& energy = *m_model.elastic_terms()[size_t(term)];
        const int K = energy.nodes_per_element();
        const int* nodes = energy.element_nodes(e);
        double g[3 * kMaxNodes];
        for (Index p = 0; p < num_poses(); ++p) {
            energy.element_gradient(e, m_poses[size_t(p)], g);
            auto block = a.segment(p * m_d, m_d);
            block.setZero();
            for (int k = 0; k < K; ++k)
                block.noalias() += m_U.middleRows<3>(3 * Index(nodes[k])).transpose() *
                                   Eigen::Map<const Vector3d>(g + 3 * k);
            block *= m_inv_norms[size_t(p)];
        }
    }

    /// Σ_e w_e E_e and the exact E at every pose.
    std::pair<VectorXd, VectorXd> energies(const Cubature& cubature) const
    {
        VectorXd approx(num_poses()), exact(num_poses());
        for (Index p = 0; p < num_poses(); ++p) {
            approx[p] = cubature_energy(m_model, cubature, m_poses[size_t(p)], nullptr);
            exact[p] = m_model.elastic_energy(m_poses[size_t(p)]);
        }
        return {approx, exact};
    }

private:
    const PhysicsModel& m_model;
    const MatrixXd& m_U;
    Index m_d;
    std::vector<VectorXd> m_poses;
    std::vector<double> m_inv_norms;
    VectorXd m_b;
};

/// At most `count` columns of `poses`, evenly spaced (first and last included).
MatrixXd spaced_columns(const MatrixXd& poses, int count)
{
    if (poses.cols() <= count) return poses;
    MatrixXd out(poses.rows(), count);
    for (int k = 0; k < count; ++k) {
        const Index j = count == 1 ? 0 : Index(std::llround(double(k) * double(poses.cols() - 1) / double(count - 1)));
        out.col(k) = poses.col(j);
    }
    return out;
}

} // namespace

Cubature Cubature::all_elements(const PhysicsModel& model)
{
    Cubature c;
    for (size_t t = 0; t < model.elastic_terms().size(); ++t)
        for (Index e = 0; e < model.elastic_terms()[t]->num_elements(); ++e) c.elements.push_back({int(t), e, 1.0});
    c.reached_tolerance = true;
    c.stop_reason = "every element";
    return c;
}

void Cubature::save(h5::File& f) const
{
    const Index n = Index(elements.size());
    VectorXi terms(n), ids(n);
    VectorXd weights(n);
    for (Index i = 0; i < n; ++i) {
        terms[i] = elements[size_t(i)].term;
        ids[i] = int(elements[size_t(i)].element);
        weights[i] = elements[size_t(i)].weight;
    }
    f.write("cubature.terms", terms);
    f.write("cubature.elements", ids);
    f.write("cubature.weights", weights);
    f.set_attribute("/", "cubature.format", std::string(kFormat));
    f.set_attribute("/", "cubature.training_error", training_error);
    f.set_attribute("/", "cubature.training_poses", (long long)training_poses);
    f.set_attribute("/", "cubature.seconds", seconds);
    f.set_attribute("/", "cubature.reached_tolerance", (long long)(reached_tolerance ? 1 : 0));
    f.set_attribute("/", "cubature.stop_reason", stop_reason);
}

Cubature Cubature::load(const h5::File& f, const PhysicsModel& model)
{
    const std::string& path = f.path();
    if (!f.has_attribute("/", "cubature.format") || f.attribute_string("/", "cubature.format") != kFormat)
        throw IoError(path + ": holds no cubature (attribute cubature.format is not '" + std::string(kFormat) + "')");
    const VectorXi terms = f.read_vector_int("cubature.terms");
    const VectorXi ids = f.read_vector_int("cubature.elements");
    const VectorXd weights = f.read_vector("cubature.weights");
    if (ids.size() != terms.size() || weights.size() != terms.size())
        throw IoError(path + ": cubature.terms, cubature.elements and cubature.weights differ in length");
    Cubature c;
    const auto& elastic = model.elastic_terms();
    for (Index i = 0; i < terms.size(); ++i) {
        if (terms[i] < 0 || size_t(terms[i]) >= elastic.size() || ids[i] < 0 ||
            ids[i] >= elastic[size_t(terms[i])]->num_elements() || !(weights[i] >= 0.0) || !std::isfinite(weights[i]))
            throw IoError(path + ": cubature entry " + std::to_string(i) + " (term " + std::to_string(terms[i]) +
                          ", element " + std::to_string(ids[i]) + ", weight " + std::to_string(weights[i]) +
                          ") does not exist in the scene or has a negative weight");
        c.elements.push_back({terms[i], Index(ids[i]), weights[i]});
    }
    c.training_error = f.attribute_double("/", "cubature.training_error");
    c.training_poses = int(f.attribute_int("/", "cubature.training_poses"));
    c.seconds = f.attribute_double("/", "cubature.seconds");
    c.reached_tolerance = f.attribute_int("/", "cubature.reached_tolerance") != 0;
    c.stop_reason = f.attribute_string("/", "cubature.stop_reason");
    return c;
}

double cubature_energy(const PhysicsModel& model, const Cubature& cubature, const VectorXd& x, VectorXd* gradient)
{
    double E = 0.0;
    if (gradient) gradient->setZero(x.size());
    double g[3 * kMaxNodes];
    for (const CubatureElement& c : cubature.elements) {
        const Energy& energy = *model.elastic_terms()[size_t(c.term)];
        E += c.weight * energy.element_value(c.element, x);
        if (gradient) {
            energy.element_gradient(c.element, x, g);
            const int* nodes = energy.element_nodes(c.element);
            for (int k = 0; k < energy.nodes_per_element(); ++k)
                gradient->segment<3>(3 * Index(nodes[k])) += c.weight * Eigen::Map<const Vector3d>(g + 3 * k);
        }
    }
    return E;
}

Cubature train_cubature(const PhysicsModel& model, const PcaSplitDecoder& decoder, const MatrixXd& poses,
                        const CubatureOptions& options)
{
    if (!(options.tolerance > 0.0)) throw ConfigError("cubature: tolerance must be positive");
    if (options.max_elements < 1) throw ConfigError("cubature: max_elements must be at least 1");
    if (options.candidates < 1) throw ConfigError("cubature: candidates must be at least 1");
    if (options.max_poses < 1) throw ConfigError("cubature: max_poses must be at least 1");
    for (const auto& term : model.elastic_terms())
        if (term->nodes_per_element() > kMaxNodes)
            throw Error("cubature: elements of " + term->name() + " have more than " + std::to_string(kMaxNodes) +
                        " vertices");
    Timer timer;
    const ForceSystem system(model, decoder, spaced_columns(poses, options.max_poses));
    if (system.num_poses() == 0)
        throw ConfigError("cubature: none of the " + std::to_string(poses.cols()) +
                          " training poses has a non-zero reduced elastic force");
    const ElementIndex index(model);
    const VectorXd& b = system.b();
    const Index rows = b.size();
    const double b_norm = b.norm();

    Cubature result;
    result.training_poses = int(system.num_poses());
    std::vector<Index> selected;           // global element ids, in order of selection
    std::vector<char> is_selected(size_t(index.total()), 0);
    MatrixXd A(rows, 0);                   // selected columns
    MatrixXd G(0, 0);                      // AᵀA
    VectorXd c(0);                         // Aᵀb
    VectorXd w;
    VectorXd r = b;
    Rng rng(options.seed);
    std::vector<Index> pool(size_t(index.total()));
    std::iota(pool.begin(), pool.end(), Index(0));
    double error = 1.0;
    result.stop_reason = "tolerance";
    while (error > options.tolerance) {
        if (Index(selected.size()) >= options.max_elements) {
            result.stop_reason = "element cap";
            break;
        }
        if (Index(selected.size()) >= index.total()) {
            result.stop_reason = "every element";
            break;
        }
        // A random subset of the unselected elements (partial Fisher–Yates on the pool).
        pool.erase(std::remove_if(pool.begin(), pool.end(), [&](Index g) { return is_selected[size_t(g)] != 0; }),
                   pool.end());
        Index m = std::min<Index>(options.candidates, Index(pool.size()));
        for (Index k = 0; k < m; ++k) std::swap(pool[size_t(k)], pool[size_t(k + rng.index(Index(pool.size()) - k))]);
        // Score the first m of the pool; if none of the random subset correlates positively
        // with the residual, score every remaining element once before giving up.
        VectorXd scores;
        Index best = 0;
        for (int pass = 0; pass < 2; ++pass) {
            scores.resize(m);
#pragma omp parallel
            {
                VectorXd a(rows);
#pragma omp for schedule(dynamic, 8)
                for (Index k = 0; k < m; ++k) {
                    const auto [term, e] = index.locate(pool[size_t(k)]);
                    system.column(term, e, a);
                    const double n = a.norm();
                    scores[k] = n > 0.0 ? a.dot(r) / n : -1.0;
                }
            }
            scores.maxCoeff(&best);
            if (scores[best] > 0.0 || m == Index(pool.size())) break;
            m = Index(pool.size());
        }
        if (!(scores[best] > 0.0)) {  // nothing left that reduces the residual
            result.stop_reason = "no correlated element";
            break;
        }
        const Index g = pool[size_t(best)];
        const auto [term, e] = index.locate(g);
        VectorXd a(rows);
        system.column(term, e, a);
        selected.push_back(g);
        is_selected[size_t(g)] = 1;
        const Index k = Index(selected.size());
        A.conservativeResize(rows, k);
        A.col(k - 1) = a;
        const VectorXd Ata = A.transpose() * a;
        G.conservativeResize(k, k);
        G.row(k - 1) = Ata.transpose();
        G.col(k - 1) = Ata;
        c.conservativeResize(k);
        c[k - 1] = a.dot(b);
        const NnlsResult nn = nnls_gram(G, c);
        w = nn.w;
        r = b - A * w;
        error = r.norm() / b_norm;
    }
    result.training_error = error;
    result.reached_tolerance = error <= options.tolerance;
    for (size_t i = 0; i < selected.size(); ++i) {
        if (!(w[Index(i)] > 0.0)) continue;
        const auto [term, e] = index.locate(selected[i]);
        result.elements.push_back({term, e, w[Index(i)]});
    }
    result.seconds = timer.seconds();
    return result;
}

CubatureAccuracy cubature_accuracy(const PhysicsModel& model, const PcaSplitDecoder& decoder, const Cubature& cubature,
                                   const MatrixXd& poses)
{
    const ForceSystem system(model, decoder, poses);
    CubatureAccuracy acc;
    if (system.num_poses() == 0) return acc;
    const VectorXd& b = system.b();
    VectorXd approx = VectorXd::Zero(b.size()), a(b.size());
    for (const CubatureElement& c : cubature.elements) {
        system.column(c.term, c.element, a);
        approx += c.weight * a;
    }
    acc.force_error = (approx - b).norm() / b.norm();
    const auto [E_approx, E_exact] = system.energies(cubature);
    acc.energy_error = (E_approx - E_exact).cwiseAbs().sum() / std::max(E_exact.cwiseAbs().sum(), 1e-300);
    return acc;
}

} // namespace lb
