#include "latent/latent_potential.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.hpp"
#include "core/parallel.hpp"
#include "energy/inertia_energy.hpp"

namespace lb {

LatentPotential::LatentPotential(const PhysicsModel& model, Autoencoder& autoencoder, double penalty_weight,
                                 bool overwrite_dirichlet)
    : m_model(model),
      m_autoencoder(autoencoder),
      m_penalty_weight(applied_penalty_weight(model, penalty_weight)),
      m_overwrite_dirichlet(overwrite_dirichlet)
{
    const int threads = std::max(1, omp_get_max_threads());
    m_potentials.reserve(size_t(threads));
    for (int i = 0; i < threads; ++i) m_potentials.emplace_back(model, m_penalty_weight);
    m_lane_potentials.reserve(size_t(threads) * Energy::kColumnLanes);
    for (int i = 0; i < threads * Energy::kColumnLanes; ++i) m_lane_potentials.emplace_back(model, m_penalty_weight);
    m_gradients.resize(size_t(threads));
    m_positions.resize(size_t(threads));
    m_columns.resize(size_t(threads));
}

double LatentPotential::value(const Eigen::Ref<const VectorXd>& z, const Eigen::Ref<const VectorXd>& bc_targets,
                              const Eigen::Ref<const VectorXd>& x_prev, const Eigen::Ref<const VectorXd>& x_prev2)
{
    return evaluate_columns(z, bc_targets, checked_x_tilde("value", 1, x_prev, x_prev2), {}, false).energies[0];
}

double LatentPotential::value_and_gradient(const Eigen::Ref<const VectorXd>& z,
                                           const Eigen::Ref<const VectorXd>& bc_targets,
                                           const Eigen::Ref<const VectorXd>& x_prev,
                                           const Eigen::Ref<const VectorXd>& x_prev2, VectorXd& grad_z)
{
    LatentEnergyOptions options;
    options.gradient = true;
    LatentEnergies r =
        evaluate_columns(z, bc_targets, checked_x_tilde("value_and_gradient", 1, x_prev, x_prev2), options, false);
    grad_z = r.grad_z.col(0);
    return r.energies[0];
}

LatentEnergies LatentPotential::evaluate(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                         const Eigen::Ref<const MatrixXd>& X_prev,
                                         const Eigen::Ref<const MatrixXd>& X_prev2, const LatentEnergyOptions& options)
{
    return evaluate_columns(Z, bc_targets, checked_x_tilde("evaluate", Z.cols(), X_prev, X_prev2), options, true);
}

LatentEnergies LatentPotential::evaluate_tilde(const Eigen::Ref<const MatrixXd>& Z,
                                               const Eigen::Ref<const MatrixXd>& bc_targets,
                                               const Eigen::Ref<const MatrixXd>& X_tilde,
                                               const LatentEnergyOptions& options)
{
    return evaluate_columns(Z, bc_targets, X_tilde, options, true);
}

namespace {
std::string shape(const Eigen::Ref<const MatrixXd>& m) { return std::to_string(m.rows()) + "×" + std::to_string(m.cols()); }
} // namespace

MatrixXd LatentPotential::checked_x_tilde(const char* caller, Index B, const Eigen::Ref<const MatrixXd>& X_prev,
                                          const Eigen::Ref<const MatrixXd>& X_prev2) const
{
    const Index n_dofs = m_model.num_dofs();
    if (X_prev.rows() != n_dofs || X_prev.cols() != B || X_prev2.rows() != n_dofs || X_prev2.cols() != B)
        throw Error(std::string("LatentPotential::") + caller + ": x_prev " + shape(X_prev) + ", x_prev2 " +
                    shape(X_prev2) + "; expected " + std::to_string(n_dofs) + " × " + std::to_string(B) + " each");
    return inertial_target(X_prev, X_prev2);
}

LatentEnergies LatentPotential::evaluate_columns(const Eigen::Ref<const MatrixXd>& Z,
                                                 const Eigen::Ref<const MatrixXd>& bc_targets,
                                                 const Eigen::Ref<const MatrixXd>& X_tilde,
                                                 const LatentEnergyOptions& options, bool check_finite)
{
    const Index B = Z.cols();
    LatentEnergies out;
    out.energies.resize(B);
    out.grad_x.resize(options.gradient ? m_model.num_dofs() : 0, options.gradient ? B : 0);
    out.grad_z.resize(options.gradient ? Z.rows() : 0, options.gradient ? B : 0);
    out.objective = evaluate_into(Z, bc_targets, X_tilde, options.weights, options.normalization, options.gradient,
                                  check_finite, out.energies, out.grad_x, out.grad_z);
    if (options.decoded) out.X = m_decoded.view();
    return out;
}

double LatentPotential::objective_tilde(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                        const Eigen::Ref<const MatrixXd>& X_tilde,
                                        const Eigen::Ref<const VectorXd>& weights, double normalization,
                                        bool gradient, Eigen::Ref<MatrixXd> grad_z)
{
    const Index B = Z.cols();
    auto energies = m_energies.resize(B, 1).col(0);
    auto grad_x = m_grad_x.resize(gradient ? m_model.num_dofs() : 0, gradient ? B : 0);
    if (gradient && (grad_z.rows() != Z.rows() || grad_z.cols() != B))
        throw Error("LatentPotential::objective_tilde: grad_z " + shape(grad_z) + ", expected " + shape(Z));
    return evaluate_into(Z, bc_targets, X_tilde, weights, normalization, gradient, true, energies, grad_x, grad_z);
}

double LatentPotential::evaluate_into(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                      const Eigen::Ref<const MatrixXd>& X_tilde,
                                      const Eigen::Ref<const VectorXd>& weights, double normalization,
                                      bool gradient, bool check_finite, Eigen::Ref<VectorXd> energies,
                                      Eigen::Ref<MatrixXd> grad_x, Eigen::Ref<MatrixXd> grad_z)
{
    const Index B = Z.cols();
    const Index n_dofs = m_model.num_dofs();
    const Index n_targets = 3 * Index(m_model.bc_indices().size());
    if (Z.rows() != m_autoencoder.latent_dim() || bc_targets.rows() != n_targets || bc_targets.cols() != B ||
        X_tilde.rows() != n_dofs || X_tilde.cols() != B || (weights.size() != 0 && weights.size() != B))
        throw Error("LatentPotential: shapes z " + shape(Z) + ", bc_targets " + shape(bc_targets) + ", x_tilde " +
                    shape(X_tilde) + ", weights " + std::to_string(weights.size()) + "; expected " +
                    std::to_string(m_autoencoder.latent_dim()) + ", " + std::to_string(n_targets) + " and " +
                    std::to_string(n_dofs) + " rows, as many columns, 0 or " + std::to_string(B) + " weights");
    Eigen::Map<MatrixXd> X = m_decoded.resize(n_dofs, B);
    decode(Z, bc_targets, X, /*record=*/gradient);
    const double objective =
        energies_into(X, bc_targets, X_tilde, weights, normalization, gradient, check_finite, energies, grad_x);
    if (gradient) {
        if (m_overwrite_dirichlet) {  // x_B = x*_B does not depend on z
            for (int v : m_model.bc_indices()) grad_x.middleRows<3>(3 * Index(v)).setZero();
        }
        if (decoder_frozen())
            frozen_vjp(grad_x, bc_targets, grad_z);
        else
            grad_z = m_autoencoder.decoder_vjp(Z, grad_x, bc_targets);
    }
    return objective;
}

void LatentPotential::energies_of(const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                                  const Eigen::Ref<const MatrixXd>& X_tilde, const LatentEnergyOptions& options,
                                  bool check_finite, LatentEnergies& out)
{
    const Index B = X.cols();
    out.energies.resize(B);
    out.grad_x.resize(options.gradient ? X.rows() : 0, options.gradient ? B : 0);
    out.objective = energies_into(X, bc_targets, X_tilde, options.weights, options.normalization, options.gradient,
                                  check_finite, out.energies, out.grad_x);
}

double LatentPotential::energies_into(const Eigen::Ref<const MatrixXd>& X, const Eigen::Ref<const MatrixXd>& bc_targets,
                                      const Eigen::Ref<const MatrixXd>& X_tilde,
                                      const Eigen::Ref<const VectorXd>& sample_weights, double normalization,
                                      bool gradient, bool check_finite, Eigen::Ref<VectorXd> energies,
                                      Eigen::Ref<MatrixXd> grad_x)
{
    const Index B = X.cols();
    // The objective's weights w_i / n: divided (not multiplied by 1/n) so the numbers are
    // those of the integrator loss written out before this class existed.
    auto weights = m_weights.resize(B, 1).col(0);
    if (sample_weights.size() == 0)
        weights.setOnes();
    else
        weights = sample_weights;
    auto gradient_scale = m_gradient_scale.resize(B, 1).col(0);
    gradient_scale = weights / normalization;
    // With gradients, whole groups of kColumnLanes columns take the column pass (the elastic
    // terms vectorised over the samples); the rest one column at a time. Same numbers.
    constexpr Index W = Energy::kColumnLanes;
    const bool column_pass = gradient && std::any_of(m_potentials[0].terms().terms().begin(),
                                                     m_potentials[0].terms().terms().end(),
                                                     [](const WeightedEnergy& t) { return t.energy->has_column_pass(); });
    const Index groups = column_pass ? B / W : 0;
    const Index single = groups * W;  // the first column done alone
    // Every thread's workspaces sized here, not by the first job a thread happens to draw
    // (dynamic schedule): a thread's first job of either kind can come batches later.
    const Index n = X.rows();
    for (std::size_t t = 0; t < m_columns.size(); ++t) {
        m_positions[t].resize(n);
        m_gradients[t].resize(n);
        if (column_pass) {
            ColumnWorkspace& ws = m_columns[t];
            ws.X.resize(n * W);
            ws.G.resize(n * W);
            ws.g.resize(W);
            for (VectorXd& g : ws.g) g.resize(n);
        }
    }
    parallel_for(groups + (B - single), true, [&](Index job) {
        if (job < groups) {
            energies_of_columns(job * W, X, bc_targets, X_tilde, gradient_scale, energies, grad_x);
            return;
        }
        const Index i = single + (job - groups);
        IncrementalPotential& pot = m_potentials[size_t(omp_get_thread_num())];
        VectorXd& xt = m_positions[size_t(omp_get_thread_num())];  // reused: no allocation per sample
        xt = X.col(i);
        set_column_state(pot, i, bc_targets, X_tilde);
        if (gradient) {
            VectorXd& g = m_gradients[size_t(omp_get_thread_num())];  // reused: no allocation per sample
            energies[i] = pot.value_gradient(xt, g);
            grad_x.col(i) = g * gradient_scale[i];
        } else {
            energies[i] = pot.value(xt);
        }
    }, /*dynamic=*/true);
    if (check_finite && !energies.allFinite()) {
        Index column = 0;
        while (std::isfinite(energies[column])) ++column;
        throw NonFinitePotential(column, energies[column]);
    }
    return weights.dot(energies) / normalization;
}

void LatentPotential::energies_of_columns(Index c0, const Eigen::Ref<const MatrixXd>& X,
                                          const Eigen::Ref<const MatrixXd>& bc_targets,
                                          const Eigen::Ref<const MatrixXd>& X_tilde,
                                          const Eigen::Ref<const VectorXd>& gradient_scale,
                                          Eigen::Ref<VectorXd> energies, Eigen::Ref<MatrixXd> grad_x)
{
    constexpr int W = Energy::kColumnLanes;
    const int thread = omp_get_thread_num();
    IncrementalPotential* pots = &m_lane_potentials[size_t(thread) * W];
    for (int l = 0; l < W; ++l) set_column_state(pots[l], c0 + l, bc_targets, X_tilde);
    ColumnWorkspace& ws = m_columns[size_t(thread)];
    VectorXd& x = m_positions[size_t(thread)];
    const Index n = X.rows();
    assert(ws.X.size() == n * W && ws.G.size() == n * W && ws.g.size() == size_t(W));  // sized by energies_into
    for (int l = 0; l < W; ++l) ws.g[size_t(l)].setZero(n);
    // Transposes row by row: each row of the 3N × W block is one cache line.
    auto to_rows = [n](const auto& column, double* rows) {
        for (Index r = 0; r < n; ++r) {
            for (int l = 0; l < W; ++l) rows[r * W + l] = column(l)[r];
        }
    };
    auto to_columns = [n](const double* rows, std::vector<VectorXd>& columns) {
        for (Index r = 0; r < n; ++r) {
            for (int l = 0; l < W; ++l) columns[size_t(l)][r] = rows[r * W + l];
        }
    };
    to_rows([&](int l) { return X.col(c0 + l).data(); }, ws.X.data());
    double sums[W] = {};
    // The terms in their order; the column-pass ones (elastic) are shared by every lane's
    // potential, the others (inertia, penalty) are the lane's own.
    const std::vector<WeightedEnergy>& terms = pots[0].terms().terms();
    for (size_t k = 0; k < terms.size();) {
        size_t end = k;
        if (terms[k].energy->has_column_pass()) {
            // A run of column-pass terms on the transposed gradients.
            to_rows([&](int l) { return ws.g[size_t(l)].data(); }, ws.G.data());
            for (; end < terms.size() && terms[end].energy->has_column_pass(); ++end) {
                double values[W] = {};
                terms[end].energy->add_value_gradient_columns(ws.X.data(), terms[end].weight, ws.G.data(), values);
                for (int l = 0; l < W; ++l) sums[l] += terms[end].weight * values[l];
            }
            to_columns(ws.G.data(), ws.g);
        } else {
            // A run of the others (inertia, gravity, penalty), column by column, each with its
            // lane's potential.
            while (end < terms.size() && !terms[end].energy->has_column_pass()) ++end;
            for (int l = 0; l < W; ++l) {
                x = X.col(c0 + l);
                const std::vector<WeightedEnergy>& own = pots[l].terms().terms();
                for (size_t j = k; j < end; ++j)
                    sums[l] += own[j].weight * own[j].energy->add_value_gradient(x, own[j].weight, ws.g[size_t(l)]);
            }
        }
        k = end;
    }
    for (int l = 0; l < W; ++l) {
        energies[c0 + l] = sums[l];
        grad_x.col(c0 + l) = ws.g[size_t(l)] * gradient_scale[c0 + l];
    }
}

void LatentPotential::set_column_state(IncrementalPotential& pot, Index i, const Eigen::Ref<const MatrixXd>& bc_targets,
                                       const Eigen::Ref<const MatrixXd>& X_tilde)
{
    pot.set_x_tilde(X_tilde.col(i));
    pot.set_bc_targets(Eigen::Map<const MatrixX3d>(bc_targets.col(i).data(), bc_targets.rows() / 3, 3));
}

LatentEnergies LatentPotential::evaluate_positions(const Eigen::Ref<const MatrixXd>& X,
                                                   const Eigen::Ref<const MatrixXd>& bc_targets,
                                                   const Eigen::Ref<const MatrixXd>& X_prev,
                                                   const Eigen::Ref<const MatrixXd>& X_prev2,
                                                   const LatentEnergyOptions& options)
{
    const Index B = X.cols();
    const Index n_dofs = m_model.num_dofs();
    const Index n_targets = 3 * Index(m_model.bc_indices().size());
    if (X.rows() != n_dofs || bc_targets.rows() != n_targets || bc_targets.cols() != B ||
        (options.weights.size() != 0 && options.weights.size() != B))
        throw Error("LatentPotential::evaluate_positions: expected x of " + std::to_string(n_dofs) +
                    " rows, bc_targets of " + std::to_string(n_targets) + " rows, as many columns and 0 or B weights");
    LatentEnergies out;
    energies_of(X, bc_targets, checked_x_tilde("evaluate_positions", B, X_prev, X_prev2), options, true, out);
    return out;
}

void LatentPotential::freeze_decoder(bool float32)
{
    m_frozen.reset();
    m_frozen_float.reset();
    if (float32)
        m_frozen_float = std::make_unique<nn::InferenceNetwork>(m_autoencoder.decoder());
    else
        m_frozen = std::make_unique<nn::InferenceNetworkD>(m_autoencoder.decoder());
}

void LatentPotential::frozen_positions(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                                       bool record, Eigen::Ref<MatrixXd> X)
{
    if (m_frozen) {
        positions_of(m_frozen->forward_batch(Z, record), bc_targets, X);
        return;
    }
    auto Zf = m_float_in.resize(Z.rows(), Z.cols());
    Zf = Z.cast<float>();
    positions_of(m_frozen_float->forward_batch(Zf, record), bc_targets, X);
}

void LatentPotential::frozen_vjp(const Eigen::Ref<const MatrixXd>& grad_x, const Eigen::Ref<const MatrixXd>& bc_targets,
                                 Eigen::Ref<MatrixXd> grad_z)
{
    const BcRelativeEncoding& encoding = m_autoencoder.encoding();
    if (m_frozen) {
        auto G = m_feature_grad.resize(encoding.num_features(), grad_x.cols());
        encoding.gradient_to_features(grad_x, bc_targets, G);
        grad_z = m_frozen->vjp_batch(G);
        return;
    }
    auto G = m_float_in.resize(encoding.num_features(), grad_x.cols());
    encoding.gradient_to_features(grad_x, bc_targets, G);
    grad_z = m_frozen_float->vjp_batch(G).cast<double>();
}

MatrixXd LatentPotential::decode(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets)
{
    MatrixXd X(m_model.num_dofs(), Z.cols());
    decode(Z, bc_targets, X);
    return X;
}

void LatentPotential::decode(const Eigen::Ref<const MatrixXd>& Z, const Eigen::Ref<const MatrixXd>& bc_targets,
                             Eigen::Ref<MatrixXd> X, bool record)
{
    if (decoder_frozen())
        frozen_positions(Z, bc_targets, record, X);
    else
        positions_of(m_autoencoder.decode_features(Z), bc_targets, X);
}

template <typename Features>
void LatentPotential::positions_of(const Features& features, const Eigen::Ref<const MatrixXd>& bc_targets,
                                   Eigen::Ref<MatrixXd> X) const
{
    m_autoencoder.encoding().to_positions(features, bc_targets, X);
    if (m_overwrite_dirichlet) {
        for (Index i = 0; i < X.cols(); ++i) overwrite_dirichlet(m_model.bc_indices(), bc_targets.col(i), X.col(i));
    }
}

} // namespace lb
