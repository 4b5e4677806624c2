#include "baselines/tan_physics_mlp/tan_losses.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"

namespace lb {

namespace {

enum Column { kPositions = 0, kTargets = 1, kParams = 2 };

} // namespace

TanLosses::TanLosses(const PhysicsModel& model, const Dataset& data, Autoencoder& autoencoder, double penalty_weight)
    : m_model(model), m_ae(autoencoder), m_potential(model, autoencoder, penalty_weight)
{
    for (const SequenceData& s : data.sequences) {
        const Index T = std::min<Index>(s.train_frames, s.num_frames());
        if (T < 3) continue;
        TanSequence seq;
        seq.X = s.positions.topRows(T).transpose();
        seq.targets = s.bc_positions.topRows(T).transpose();
        seq.params = s.bc_params.topRows(T).transpose();
        m_sequences.push_back(std::move(seq));
    }
    if (m_sequences.empty())
        throw ConfigError("tan_physics_mlp: the dataset has no sequence with 3 training frames");
    m_dof_masses.resize(model.num_dofs());
    for (Index i = 0; i < model.num_vertices(); ++i) m_dof_masses.segment<3>(3 * i).setConstant(model.masses()[i]);
    const double mean_mass = model.masses().mean();
    m_energy_scale = 2.0 * model.dt() * model.dt() / (double(model.num_dofs()) * mean_mass);
}

std::vector<TanSample> TanLosses::frame_samples() const
{
    std::vector<TanSample> out;
    for (Index s = 0; s < Index(m_sequences.size()); ++s) {
        for (Index m = 2; m < m_sequences[size_t(s)].frames(); ++m) out.push_back({s, m});
    }
    return out;
}

Index TanLosses::max_window() const
{
    Index k = std::numeric_limits<Index>::max();
    for (const TanSequence& s : m_sequences) k = std::min(k, s.frames() - 2);
    return k;
}

std::vector<TanSample> TanLosses::window_samples(Index window) const
{
    std::vector<TanSample> out;
    for (Index s = 0; s < Index(m_sequences.size()); ++s) {
        for (Index t0 = 0; t0 + window + 1 < m_sequences[size_t(s)].frames(); ++t0) out.push_back({s, t0});
    }
    return out;
}

MatrixXd TanLosses::gather(const std::vector<TanSample>& batch, Index offset, int which) const
{
    const TanSequence& first = m_sequences.front();
    const MatrixXd& like = which == kPositions ? first.X : which == kTargets ? first.targets : first.params;
    MatrixXd out(like.rows(), Index(batch.size()));
    for (Index b = 0; b < out.cols(); ++b) {
        const TanSample& s = batch[size_t(b)];
        const TanSequence& seq = m_sequences[size_t(s.sequence)];
        const MatrixXd& src = which == kPositions ? seq.X : which == kTargets ? seq.targets : seq.params;
        out.col(b) = src.col(s.frame + offset);
    }
    return out;
}

MatrixXd TanLosses::mlp_inputs(const MatrixXd& z1, const MatrixXd& z2, const std::vector<TanSample>& batch,
                               Index offset) const
{
    const MatrixXd p = gather(batch, offset, kParams), p1 = gather(batch, offset - 1, kParams),
                   p2 = gather(batch, offset - 2, kParams);
    MatrixXd in(2 * z1.rows() + 3 * p.rows(), z1.cols());
    in << z1, z2, p, p1, p2;
    return in;
}

MatrixXd TanLosses::encode_triples(const std::vector<TanSample>& batch)
{
    const Index B = Index(batch.size());
    MatrixXd X(m_model.num_dofs(), 3 * B);
    X << gather(batch, 0, kPositions), gather(batch, -1, kPositions), gather(batch, -2, kPositions);
    return m_ae.encoder().forward(m_ae.encoding().to_features(X), false);
}

double TanLosses::position_losses(const MatrixXd& X_hat, const std::vector<TanSample>& batch, const TanWeights& w,
                                  bool gradient, MatrixXd& grad_x, TanLossParts& parts)
{
    const Index B = Index(batch.size());
    const double dofs = double(m_model.num_dofs());
    const MatrixXd residual = X_hat.leftCols(B) - gather(batch, 0, kPositions);
    parts.recon = residual.squaredNorm() / (dofs * double(B));
    // x̂_{m−1}, x̂_{m−2} enter as constants (the stop-gradient of Tan eq. 5 / 11).
    LatentEnergyOptions o;
    o.gradient = gradient;
    o.weights = VectorXd::Constant(B, w.ephys * m_energy_scale);
    o.normalization = double(B);
    const LatentEnergies e = m_potential.evaluate_positions(X_hat.leftCols(B), gather(batch, 0, kTargets),
                                                            X_hat.middleCols(B, B), X_hat.rightCols(B), o);
    parts.ephys = m_energy_scale * e.energies.sum() / double(B);
    if (gradient) grad_x = (2.0 * w.recon / (dofs * double(B))) * residual + e.grad_x;
    return w.recon * parts.recon + w.ephys * parts.ephys;
}

double TanLosses::embedding_loss(const std::vector<TanSample>& batch, const TanWeights& w, bool gradient,
                                 TanLossParts* parts_out)
{
    const Index B = Index(batch.size());
    TanLossParts parts;
    const MatrixXd Z = encode_triples(batch);
    MatrixXd T(3 * Index(m_ae.encoding().bc_indices().size()), 3 * B);
    T << gather(batch, 0, kTargets), gather(batch, -1, kTargets), gather(batch, -2, kTargets);
    const MatrixXd X_hat = m_ae.encoding().to_positions(m_ae.decoder().forward(Z, false), T);
    MatrixXd grad_x;
    const double loss = position_losses(X_hat, batch, w, gradient, grad_x, parts);
    if (gradient) {
        MatrixXd dF = MatrixXd::Zero(m_ae.num_features(), 3 * B);
        dF.leftCols(B) = m_ae.encoding().gradient_to_features(grad_x, T.leftCols(B));
        // The x̂_{m−1}, x̂_{m−2} columns get no gradient: stopped.
        m_ae.encoder().backward(m_ae.decoder().backward(dF, true), true);
    }
    if (parts_out) *parts_out = parts;
    return loss;
}

double TanLosses::mlp_loss(LatentMlpModel& mlp, const std::vector<TanSample>& batch, Index window,
                           const TanWeights& w, bool stop_gradient, bool gradient, TanLossParts* parts_out)
{
    const Index B = Index(batch.size()), K = window, L = m_ae.latent_dim();
    const double n = double(B * K);
    TanLossParts parts;
    // Ground-truth latents of frames t0 + j, j = 0 … K+1 (frozen encoder).
    std::vector<MatrixXd> z_gt(size_t(K + 2));
    for (Index j = 0; j < K + 2; ++j) z_gt[size_t(j)] = m_ae.encode(gather(batch, j, kPositions));

    // L_sim: one-step predictions from ground-truth latents (teacher forcing), all K steps at once.
    {
        MatrixXd in(mlp.input_dim(), B * K), z1(L, B * K), target(L, B * K);
        for (Index k = 0; k < K; ++k) {
            const Index j = k + 2;
            in.middleCols(k * B, B) = mlp_inputs(z_gt[size_t(j - 1)], z_gt[size_t(j - 2)], batch, j);
            z1.middleCols(k * B, B) = z_gt[size_t(j - 1)];
            target.middleCols(k * B, B) = z_gt[size_t(j)];
        }
        const MatrixXd diff = mlp.forward(in, z1, gradient) - target;
        parts.sim = diff.squaredNorm() / n;
        if (gradient && w.sim != 0.0) mlp.backward((2.0 * w.sim / n) * diff);
    }

    // L_mphys: unroll from the ground truth of frames t0, t0+1.
    std::vector<MatrixXd> Z(size_t(K + 2)), X(size_t(K + 2)), inputs(size_t(K + 2)), dZ(size_t(K + 2));
    std::vector<MatrixXd> grad_prev(size_t(K + 2)), grad_prev2(size_t(K + 2));
    Z[0] = z_gt[0];
    Z[1] = z_gt[1];
    X[0] = m_ae.decode(Z[0], gather(batch, 0, kTargets));
    X[1] = m_ae.decode(Z[1], gather(batch, 1, kTargets));
    const double h2 = m_model.dt() * m_model.dt();
    const double weight = w.mphys * m_energy_scale;
    double energy_sum = 0.0;
    for (Index j = 2; j < K + 2; ++j) {
        const size_t u = size_t(j);
        inputs[u] = mlp_inputs(Z[u - 1], Z[u - 2], batch, j);
        Z[u] = mlp.forward(inputs[u], Z[u - 1], false);
        LatentEnergyOptions o;
        o.gradient = gradient;
        o.decoded = true;
        o.weights = VectorXd::Constant(B, weight);
        o.normalization = n;
        LatentEnergies e = m_potential.evaluate(Z[u], gather(batch, j, kTargets), X[u - 1], X[u - 2], o);
        energy_sum += e.energies.sum();
        X[u] = std::move(e.X);
        dZ[u] = std::move(e.grad_z);
        if (gradient && !stop_gradient) {
            // Tan eq. 8 as written: E_j also depends on x_{j−1}, x_{j−2} through the inertia
            // term ½h⁻²‖x_j − 2x_{j−1} + x_{j−2}‖²_M: ∂/∂x_{j−1} = −2 g, ∂/∂x_{j−2} = g,
            // g = M(x_j − 2x_{j−1} + x_{j−2}) / h² (times the objective's weight w / n).
            const MatrixXd g =
                (weight / (n * h2)) * (m_dof_masses.asDiagonal() * (X[u] - 2.0 * X[u - 1] + X[u - 2]));
            grad_prev[u] = -2.0 * g;
            grad_prev2[u] = g;
        }
    }
    parts.mphys = m_energy_scale * energy_sum / n;
    if (gradient) {
        dZ[0] = MatrixXd::Zero(L, B);
        dZ[1] = MatrixXd::Zero(L, B);
        if (!stop_gradient) {
            for (Index j = 2; j < K + 2; ++j) {
                const size_t u = size_t(j);
                if (j - 1 >= 2) dZ[u - 1] += m_ae.decoder_vjp(Z[u - 1], grad_prev[u], gather(batch, j - 1, kTargets));
                if (j - 2 >= 2) dZ[u - 2] += m_ae.decoder_vjp(Z[u - 2], grad_prev2[u], gather(batch, j - 2, kTargets));
            }
        }
        // Back-propagation through time; each step's forward is re-run to restore the
        // network's cache (it holds only the last forward).
        for (Index j = K + 1; j >= 2; --j) {
            const size_t u = size_t(j);
            mlp.forward(inputs[u], Z[u - 1], true);
            const MatrixXd d_in = mlp.backward(dZ[u]);
            if (j - 1 >= 2) dZ[u - 1] += d_in.topRows(L) + dZ[u];  // input z_{j−1} and the skip connection
            if (j - 2 >= 2) dZ[u - 2] += d_in.middleRows(L, L);
        }
    }
    if (parts_out) *parts_out = parts;
    return w.sim * parts.sim + w.mphys * parts.mphys;
}

double TanLosses::joint_loss(LatentMlpModel& mlp, const std::vector<TanSample>& batch, const TanWeights& w,
                             bool gradient, TanLossParts* parts_out)
{
    const Index B = Index(batch.size()), L = m_ae.latent_dim();
    TanLossParts parts;
    const MatrixXd Z = encode_triples(batch);  // [z_m, z_{m−1}, z_{m−2}]
    const MatrixXd z = Z.leftCols(B), z1 = Z.middleCols(B, B), z2 = Z.rightCols(B);
    const MatrixXd z_mlp = mlp.forward(mlp_inputs(z1, z2, batch, 0), z1, gradient);
    const MatrixXd sim_diff = z_mlp - z;
    parts.sim = sim_diff.squaredNorm() / double(B);
    // The decoder gets z′ = ½ z_m + ½ MLP(·) (Tan §VI-A), and the stopped x̂_{m−1}, x̂_{m−2}.
    MatrixXd Z_dec(L, 3 * B);
    Z_dec << 0.5 * z + 0.5 * z_mlp, z1, z2;
    MatrixXd T(3 * Index(m_ae.encoding().bc_indices().size()), 3 * B);
    T << gather(batch, 0, kTargets), gather(batch, -1, kTargets), gather(batch, -2, kTargets);
    const MatrixXd X_hat = m_ae.encoding().to_positions(m_ae.decoder().forward(Z_dec, false), T);
    MatrixXd grad_x;
    const double loss = position_losses(X_hat, batch, w, gradient, grad_x, parts) + w.sim * parts.sim;
    if (gradient) {
        MatrixXd dF = MatrixXd::Zero(m_ae.num_features(), 3 * B);
        dF.leftCols(B) = m_ae.encoding().gradient_to_features(grad_x, T.leftCols(B));
        const MatrixXd d_zp = m_ae.decoder().backward(dF, true).leftCols(B);
        const MatrixXd d_sim = (2.0 * w.sim / double(B)) * sim_diff;
        const MatrixXd d_mlp = 0.5 * d_zp + d_sim;
        const MatrixXd d_in = mlp.backward(d_mlp);
        MatrixXd dZ(L, 3 * B);
        dZ << 0.5 * d_zp - d_sim, d_in.topRows(L) + d_mlp, d_in.middleRows(L, L);
        m_ae.encoder().backward(dZ, true);
    }
    if (parts_out) *parts_out = parts;
    return loss;
}

} // namespace lb
