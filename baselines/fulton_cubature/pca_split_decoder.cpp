#include "baselines/fulton_cubature/pca_split_decoder.hpp"

#include "core/error.hpp"
#include "nn/linear.hpp"
#include "nn/network_derivatives.hpp"

namespace lb {

PcaSplitDecoder::PcaSplitDecoder(Autoencoder& autoencoder, const PhysicsModel& model)
    : m_latent_dim(autoencoder.latent_dim()), m_encoding(model.spec())
{
    if (autoencoder.encoding().frame() != EncodingFrame::translation)
        throw ConfigError(std::string("fulton: the autoencoder encodes in the boundary's rigid frame (") +
                          autoencoder.encoding().kind_name() +
                          "); the split decoder's precomputed PCA coordinates assume the translation frame "
                          "(x = U s + c(targets)); train the autoencoder with frame = \"translation\"");
    nn::Sequential& decoder = autoencoder.decoder();
    if (decoder.size() < 2) throw Error("fulton: the decoder has fewer than two layers; nothing to split");
    const auto* last = dynamic_cast<const nn::Linear*>(&decoder.layer(decoder.size() - 1));
    if (last == nullptr) throw Error("fulton: the decoder's last layer is not Linear (no PCA layer to split at)");
    if (m_encoding.num_features() != autoencoder.num_features() || model.num_dofs() != m_encoding.num_dofs())
        throw Error("fulton: the autoencoder has " + std::to_string(autoencoder.num_features()) +
                    " features, the scene " + std::to_string(m_encoding.num_features()));
    for (Index i = 0; i + 1 < decoder.size(); ++i) m_inner.add(decoder.layer(i).clone());
    m_bias = last->bias();
    const Index B = Index(model.bc_indices().size());
    m_U = m_encoding.to_positions(last->weight(), MatrixXd::Zero(3 * B, last->weight().cols()));
    const Index N = model.num_vertices();
    m_masses3.resize(3 * N);
    m_Mg.resize(3 * N);
    for (Index i = 0; i < N; ++i) {
        m_masses3.segment<3>(3 * i).setConstant(model.masses()[i]);
        m_Mg.segment<3>(3 * i) = model.masses()[i] * model.spec().gravity;
    }
    const MatrixXd MU = m_masses3.asDiagonal() * m_U;
    m_UtMU.noalias() = m_U.transpose() * MU;
    m_UtMg.noalias() = m_U.transpose() * m_Mg;
    // UᵀMA column by column: A e_j is the offset of a unit target coordinate.
    m_UtMA.resize(pca_dim(), 3 * B);
    VectorXd unit = VectorXd::Zero(3 * B), column(3 * N);
    for (Index j = 0; j < 3 * B; ++j) {
        unit[j] = 1.0;
        target_offset_into(unit, column);
        m_UtMA.col(j).noalias() = MU.transpose() * column;
        unit[j] = 0.0;
    }
}

VectorXd PcaSplitDecoder::inner(const Eigen::Ref<const VectorXd>& z)
{
    return m_inner.forward(MatrixXd(z), false).col(0);
}

VectorXd PcaSplitDecoder::vjp(const Eigen::Ref<const VectorXd>& v)
{
    return m_inner.backward(MatrixXd(v), false).col(0);
}

MatrixXd PcaSplitDecoder::inner_jacobian(const Eigen::Ref<const VectorXd>& z)
{
    return nn::jacobian(m_inner, z);
}

void PcaSplitDecoder::offset_into(const Eigen::Ref<const VectorXd>& targets, Eigen::Ref<VectorXd> c) const
{
    m_encoding.to_positions_into(m_bias, targets, c);
}

void PcaSplitDecoder::target_offset_into(const Eigen::Ref<const VectorXd>& targets, Eigen::Ref<VectorXd> c) const
{
    m_encoding.to_positions_into(VectorXd::Zero(m_bias.size()), targets, c);
}

} // namespace lb
