#include "latent/embedding_energy_loss.hpp"

#include <algorithm>

#include "core/error.hpp"

namespace lb {

EmbeddingEnergyLoss::EmbeddingEnergyLoss(const PhysicsModel& model, const Dataset& data, Autoencoder& autoencoder,
                                         double penalty_weight, const std::string& who)
    : m_model(model), m_ae(autoencoder), m_potential(model, autoencoder, penalty_weight)
{
    for (const SequenceData& s : data.sequences) {
        const Index T = std::min<Index>(s.train_frames, s.num_frames());
        if (T < 3) continue;
        FrameSequence seq;
        seq.X = s.positions.topRows(T).transpose();
        seq.targets = s.bc_positions.topRows(T).transpose();
        seq.params = s.bc_params.topRows(T).transpose();
        m_sequences.push_back(std::move(seq));
    }
    if (m_sequences.empty()) throw ConfigError(who + ": the dataset has no sequence with 3 training frames");
    m_dof_masses.resize(model.num_dofs());
    for (Index i = 0; i < model.num_vertices(); ++i) m_dof_masses.segment<3>(3 * i).setConstant(model.masses()[i]);
    m_energy_scale = 2.0 * model.dt() * model.dt() / (double(model.num_dofs()) * model.masses().mean());
}

std::vector<FrameSample> EmbeddingEnergyLoss::frame_samples() const
{
    std::vector<FrameSample> out;
    for (Index s = 0; s < Index(m_sequences.size()); ++s) {
        for (Index m = 2; m < m_sequences[size_t(s)].frames(); ++m) out.push_back({s, m});
    }
    return out;
}

MatrixXd EmbeddingEnergyLoss::gather(const std::vector<FrameSample>& batch, Index offset, FrameColumn which) const
{
    auto columns = [which](const FrameSequence& seq) -> const MatrixXd& {
        return which == FrameColumn::positions ? seq.X : which == FrameColumn::targets ? seq.targets : seq.params;
    };
    MatrixXd out(columns(m_sequences.front()).rows(), Index(batch.size()));
    for (Index b = 0; b < out.cols(); ++b) {
        const FrameSample& s = batch[size_t(b)];
        out.col(b) = columns(m_sequences[size_t(s.sequence)]).col(s.frame + offset);
    }
    return out;
}

MatrixXd EmbeddingEnergyLoss::triple_targets(const std::vector<FrameSample>& batch) const
{
    const Index B = Index(batch.size());
    MatrixXd T(3 * Index(m_ae.encoding().bc_indices().size()), 3 * B);
    T << gather(batch, 0, FrameColumn::targets), gather(batch, -1, FrameColumn::targets),
        gather(batch, -2, FrameColumn::targets);
    return T;
}

MatrixXd EmbeddingEnergyLoss::encode_triples(const std::vector<FrameSample>& batch)
{
    const Index B = Index(batch.size());
    MatrixXd X(m_model.num_dofs(), 3 * B);
    X << gather(batch, 0, FrameColumn::positions), gather(batch, -1, FrameColumn::positions),
        gather(batch, -2, FrameColumn::positions);
    return m_ae.encoder().forward(m_ae.encoding().to_features(X), false);
}

double EmbeddingEnergyLoss::position_losses(const MatrixXd& X_hat, const std::vector<FrameSample>& batch,
                                            double recon_weight, double ephys_weight, bool gradient,
                                            MatrixXd& grad_x, EmbeddingLossParts& parts)
{
    const Index B = Index(batch.size());
    const double dofs = double(m_model.num_dofs());
    const MatrixXd residual = X_hat.leftCols(B) - gather(batch, 0, FrameColumn::positions);
    parts.recon = residual.squaredNorm() / (dofs * double(B));
    // x̂_{m−1}, x̂_{m−2} enter as constants (the stop-gradient of Tan eq. 5 / 11).
    LatentEnergyOptions o;
    o.gradient = gradient;
    o.weights = VectorXd::Constant(B, ephys_weight * m_energy_scale);
    o.normalization = double(B);
    const LatentEnergies e = m_potential.evaluate_positions(X_hat.leftCols(B), gather(batch, 0, FrameColumn::targets),
                                                            X_hat.middleCols(B, B), X_hat.rightCols(B), o);
    parts.ephys = m_energy_scale * e.energies.sum() / double(B);
    if (gradient) grad_x = (2.0 * recon_weight / (dofs * double(B))) * residual + e.grad_x;
    return recon_weight * parts.recon + ephys_weight * parts.ephys;
}

double EmbeddingEnergyLoss::loss(const std::vector<FrameSample>& batch, double recon_weight, double ephys_weight,
                                 bool gradient, EmbeddingLossParts* parts_out)
{
    const Index B = Index(batch.size());
    EmbeddingLossParts parts;
    const MatrixXd Z = encode_triples(batch);
    const MatrixXd T = triple_targets(batch);
    const MatrixXd X_hat = m_ae.encoding().to_positions(m_ae.decoder().forward(Z, false), T);
    MatrixXd grad_x;
    const double value = position_losses(X_hat, batch, recon_weight, ephys_weight, gradient, grad_x, parts);
    if (gradient) {
        MatrixXd dF = MatrixXd::Zero(m_ae.num_features(), 3 * B);
        dF.leftCols(B) = m_ae.encoding().gradient_to_features(grad_x, T.leftCols(B));
        // The x̂_{m−1}, x̂_{m−2} columns get no gradient: stopped.
        m_ae.encoder().backward(m_ae.decoder().backward(dF, true), true);
    }
    if (parts_out) *parts_out = parts;
    return value;
}

FrameSampleLearner::FrameSampleLearner(std::vector<FrameSample> samples, std::vector<nn::ParameterRef> parameters,
                                       LossFn loss)
    : m_samples(std::move(samples)), m_parameters(std::move(parameters)), m_loss(std::move(loss))
{
}

double FrameSampleLearner::loss_and_gradient(const std::vector<Index>& indices, Rng&)
{
    std::vector<FrameSample> batch;
    batch.reserve(indices.size());
    for (Index i : indices) batch.push_back(m_samples[size_t(i)]);
    return m_loss(batch);
}

std::vector<nn::ParameterRef> autoencoder_parameters(Autoencoder& ae, const std::string& prefix)
{
    std::vector<nn::ParameterRef> p = ae.encoder().parameters(prefix + "encoder.");
    for (auto& q : ae.decoder().parameters(prefix + "decoder.")) p.push_back(q);
    return p;
}

} // namespace lb
