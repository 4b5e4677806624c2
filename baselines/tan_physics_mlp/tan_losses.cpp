#include "baselines/tan_physics_mlp/tan_losses.hpp"

#include <algorithm>
#include <limits>

#include "core/error.hpp"

namespace lb {

namespace {

constexpr FrameColumn kPositions = FrameColumn::positions;
constexpr FrameColumn kTargets = FrameColumn::targets;
constexpr FrameColumn kParams = FrameColumn::params;

TanLossParts tan_parts(const EmbeddingLossParts& p)
{
    TanLossParts out;
    out.recon = p.recon;
    out.ephys = p.ephys;
    return out;
}

} // namespace

TanLosses::TanLosses(const PhysicsModel& model, const Dataset& data, Autoencoder& autoencoder, double penalty_weight)
    : m_embedding(model, data, autoencoder, penalty_weight, "tan_physics_mlp")
{
}

Index TanLosses::max_window() const
{
    Index k = std::numeric_limits<Index>::max();
    for (const TanSequence& s : sequences()) k = std::min(k, s.frames() - 2);
    return k;
}

std::vector<TanSample> TanLosses::window_samples(Index window) const
{
    std::vector<TanSample> out;
    for (Index s = 0; s < Index(sequences().size()); ++s) {
        for (Index t0 = 0; t0 + window + 1 < sequences()[size_t(s)].frames(); ++t0) out.push_back({s, t0});
    }
    return out;
}

MatrixXd TanLosses::mlp_inputs(const MatrixXd& z1, const MatrixXd& z2, const std::vector<TanSample>& batch,
                               Index offset) const
{
    const MatrixXd p = m_embedding.gather(batch, offset, kParams), p1 = m_embedding.gather(batch, offset - 1, kParams),
                   p2 = m_embedding.gather(batch, offset - 2, kParams);
    MatrixXd in(2 * z1.rows() + 3 * p.rows(), z1.cols());
    in << z1, z2, p, p1, p2;
    return in;
}

double TanLosses::embedding_loss(const std::vector<TanSample>& batch, const TanWeights& w, bool gradient,
                                 TanLossParts* parts_out)
{
    EmbeddingLossParts parts;
    const double loss = m_embedding.loss(batch, w.recon, w.ephys, gradient, &parts);
    if (parts_out) *parts_out = tan_parts(parts);
    return loss;
}

double TanLosses::mlp_loss(LatentMlpModel& mlp, const std::vector<TanSample>& batch, Index window,
                           const TanWeights& w, bool stop_gradient, bool gradient, TanLossParts* parts_out)
{
    Autoencoder& ae = autoencoder();
    const Index B = Index(batch.size()), K = window, L = ae.latent_dim();
    const double n = double(B * K);
    TanLossParts parts;
    // Ground-truth latents of frames t0 + j, j = 0 … K+1 (frozen encoder).
    std::vector<MatrixXd> z_gt(size_t(K + 2));
    for (Index j = 0; j < K + 2; ++j) z_gt[size_t(j)] = ae.encode(m_embedding.gather(batch, j, kPositions));

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
    X[0] = ae.decode(Z[0], m_embedding.gather(batch, 0, kTargets));
    X[1] = ae.decode(Z[1], m_embedding.gather(batch, 1, kTargets));
    const double h2 = m_embedding.model().dt() * m_embedding.model().dt();
    const double weight = w.mphys * m_embedding.energy_scale();
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
        LatentEnergies e = m_embedding.potential().evaluate(Z[u], m_embedding.gather(batch, j, kTargets), X[u - 1], X[u - 2], o);
        energy_sum += e.energies.sum();
        X[u] = std::move(e.X);
        dZ[u] = std::move(e.grad_z);
        if (gradient && !stop_gradient) {
            // Tan eq. 8 as written: E_j also depends on x_{j−1}, x_{j−2} through the inertia
            // term ½h⁻²‖x_j − 2x_{j−1} + x_{j−2}‖²_M: ∂/∂x_{j−1} = −2 g, ∂/∂x_{j−2} = g,
            // g = M(x_j − 2x_{j−1} + x_{j−2}) / h² (times the objective's weight w / n).
            const MatrixXd g =
                (weight / (n * h2)) * (m_embedding.dof_masses().asDiagonal() * (X[u] - 2.0 * X[u - 1] + X[u - 2]));
            grad_prev[u] = -2.0 * g;
            grad_prev2[u] = g;
        }
    }
    parts.mphys = m_embedding.energy_scale() * energy_sum / n;
    if (gradient) {
        dZ[0] = MatrixXd::Zero(L, B);
        dZ[1] = MatrixXd::Zero(L, B);
        if (!stop_gradient) {
            for (Index j = 2; j < K + 2; ++j) {
                const size_t u = size_t(j);
                if (j - 1 >= 2) dZ[u - 1] += ae.decoder_vjp(Z[u - 1], grad_prev[u], m_embedding.gather(batch, j - 1, kTargets));
                if (j - 2 >= 2) dZ[u - 2] += ae.decoder_vjp(Z[u - 2], grad_prev2[u], m_embedding.gather(batch, j - 2, kTargets));
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
    Autoencoder& ae = autoencoder();
    const Index B = Index(batch.size()), L = ae.latent_dim();
    TanLossParts parts;
    const MatrixXd Z = m_embedding.encode_triples(batch);  // [z_m, z_{m−1}, z_{m−2}]
    const MatrixXd z = Z.leftCols(B), z1 = Z.middleCols(B, B), z2 = Z.rightCols(B);
    const MatrixXd z_mlp = mlp.forward(mlp_inputs(z1, z2, batch, 0), z1, gradient);
    const MatrixXd sim_diff = z_mlp - z;
    parts.sim = sim_diff.squaredNorm() / double(B);
    // The decoder gets z′ = ½ z_m + ½ MLP(·) (Tan §VI-A), and the stopped x̂_{m−1}, x̂_{m−2}.
    MatrixXd Z_dec(L, 3 * B);
    Z_dec << 0.5 * z + 0.5 * z_mlp, z1, z2;
    const MatrixXd T = m_embedding.triple_targets(batch);
    const MatrixXd X_hat = ae.encoding().to_positions(ae.decoder().forward(Z_dec, false), T);
    MatrixXd grad_x;
    EmbeddingLossParts position_parts;
    const double loss =
        m_embedding.position_losses(X_hat, batch, w.recon, w.ephys, gradient, grad_x, position_parts) +
        w.sim * parts.sim;
    parts.recon = position_parts.recon;
    parts.ephys = position_parts.ephys;
    if (gradient) {
        MatrixXd dF = MatrixXd::Zero(ae.num_features(), 3 * B);
        dF.leftCols(B) = ae.encoding().gradient_to_features(grad_x, T.leftCols(B));
        const MatrixXd d_zp = ae.decoder().backward(dF, true).leftCols(B);
        const MatrixXd d_sim = (2.0 * w.sim / double(B)) * sim_diff;
        const MatrixXd d_mlp = 0.5 * d_zp + d_sim;
        const MatrixXd d_in = mlp.backward(d_mlp);
        MatrixXd dZ(L, 3 * B);
        dZ << 0.5 * d_zp - d_sim, d_in.topRows(L) + d_mlp, d_in.middleRows(L, L);
        ae.encoder().backward(dZ, true);
    }
    if (parts_out) *parts_out = parts;
    return loss;
}

} // namespace lb
