#include "integrators/latent_mlp_integrator.hpp"

#include <tuple>
#include <utility>

#include "core/error.hpp"
#include "core/timer.hpp"
#include "sim/physics_model.hpp"
#include "io/hdf5.hpp"
#include "nn/serialization.hpp"

namespace lb {

VectorXd integrator_input(const VectorXd& z_prev, const VectorXd& z_prev2, const VectorXd& p,
                          const VectorXd& p_prev, const VectorXd& p_prev2)
{
    VectorXd in(z_prev.size() * 2 + p.size() * 3);
    in << z_prev, z_prev2, p, p_prev, p_prev2;
    return in;
}

LatentMlpModel LatentMlpModel::create(Index latent_dim, Index param_dim, const std::vector<Index>& hidden,
                                      std::uint64_t seed)
{
    LatentMlpModel m;
    m.latent_dim = latent_dim;
    m.param_dim = param_dim;
    nn::MlpSpec spec;
    spec.in_dim = m.input_dim();
    spec.hidden = hidden;
    spec.out_dim = latent_dim;
    spec.activation = nn::ActivationKind::swish;
    Rng rng(seed);
    m.network = nn::make_mlp(spec, rng);
    m.inputs = nn::Standardizer(m.input_dim());
    m.output_scale = VectorXd::Ones(latent_dim);
    return m;
}

nn::BatchView LatentMlpModel::forward(const Eigen::Ref<const MatrixXd>& inputs_raw,
                                     const Eigen::Ref<const MatrixXd>& z_prev, bool training)
{
    auto S = standardized.resize(inputs_raw.rows(), inputs_raw.cols());
    inputs.apply(inputs_raw, S);
    const nn::BatchView out = network.forward(S, training);
    prediction.resize(z_prev.rows(), z_prev.cols()) = z_prev + output_scale.asDiagonal() * out;
    return std::as_const(prediction).view();
}

nn::BatchView LatentMlpModel::backward(const Eigen::Ref<const MatrixXd>& dZ)
{
    // z = z_prev + s ⊙ out: ∂L/∂out = s ⊙ ∂L/∂z (z_prev is an input, not a parameter).
    auto d_out = output_adjoint.resize(dZ.rows(), dZ.cols());
    d_out = output_scale.asDiagonal() * dZ;
    const nn::BatchView d_standardized = network.backward(d_out, true);
    auto d_inputs = input_gradient.resize(d_standardized.rows(), d_standardized.cols());
    inputs.backward(d_standardized, d_inputs);
    return std::as_const(input_gradient).view();
}

void LatentMlpModel::save(h5::File& file, const std::string& prefix)
{
    nn::save_network(file, prefix, network, &inputs);
    file.write(prefix + "output_scale", output_scale);
    file.set_attribute("/", prefix + "latent_dim", (long long)latent_dim);
    file.set_attribute("/", prefix + "param_dim", (long long)param_dim);
    file.set_attribute("/", prefix + "loss", loss);
    file.set_attribute("/", prefix + "description", description);
    file.set_attribute("/", prefix + "overwrite_dirichlet", (long long)overwrite_dirichlet);
    file.set_attribute("/", prefix + "boundary_input", to_string(boundary.kind()));
    if (boundary.kind() != BoundaryInputKind::Velocity) file.write(prefix + "boundary_rest_targets", boundary.rest_targets());
}

LatentMlpModel LatentMlpModel::load(const h5::File& file, const std::string& prefix)
{
    LatentMlpModel m;
    nn::LoadedNetwork loaded = nn::load_network(file, prefix);
    m.network = std::move(loaded.network);
    if (!loaded.standardizer) throw IoError("'" + file.path() + "': integrator has no input standardiser");
    m.inputs = *loaded.standardizer;
    m.output_scale = file.read_vector(prefix + "output_scale");
    m.latent_dim = Index(file.attribute_int("/", prefix + "latent_dim"));
    m.param_dim = Index(file.attribute_int("/", prefix + "param_dim"));
    m.loss = file.attribute_string("/", prefix + "loss");
    m.description = file.attribute_string("/", prefix + "description");
    // Absent in files written before the option: the decoded Dirichlet vertices were kept.
    const std::string overwrite = prefix + "overwrite_dirichlet";
    m.overwrite_dirichlet = file.has_attribute("/", overwrite) && file.attribute_int("/", overwrite) != 0;
    const std::string input = prefix + "boundary_input";
    if (file.has_attribute("/", input)) {
        BoundaryInputKind kind;
        try {
            kind = boundary_input_from_string(file.attribute_string("/", input));
        } catch (const ConfigError& e) {
            throw IoError("'" + file.path() + "', '" + input + "': " + e.what());
        }
        if (kind != BoundaryInputKind::Velocity)
            m.boundary = BoundaryInput(kind, file.read_vector(prefix + "boundary_rest_targets"));
    }
    if (m.network.in_features() != m.input_dim() || m.network.out_features() != m.latent_dim ||
        m.output_scale.size() != m.latent_dim || m.boundary.size(0) > m.param_dim) {
        throw IoError("'" + file.path() + "': integrator network shapes disagree with its latent/parameter sizes");
    }
    if (!m.output_scale.allFinite())
        throw IoError("'" + file.path() + "', '" + prefix + "output_scale': non-finite value (NaN or inf)");
    return m;
}

LatentMlpIntegrator::LatentMlpIntegrator(std::string name, std::shared_ptr<Autoencoder> autoencoder,
                                         LatentMlpModel model, nn::WeightFormat weights)
    : m_name(std::move(name)), m_autoencoder(std::move(autoencoder)), m_model(std::move(model)),
      m_integrator_net(m_model.network, &m_model.inputs, weights), m_decoder_net(m_autoencoder->decoder(), nullptr, weights)
{
    if (m_model.latent_dim != m_autoencoder->latent_dim()) {
        throw Error("integrator latent size " + std::to_string(m_model.latent_dim) + " differs from the autoencoder's " +
                    std::to_string(m_autoencoder->latent_dim()));
    }
    m_input.resize(m_model.input_dim());
    m_zf.resize(m_model.latent_dim);
    m_x.resize(m_autoencoder->encoding().num_dofs());
    m_scale = m_model.output_scale.cast<float>();
}

void LatentMlpIntegrator::reset(const VectorXd& x_prev2, const BoundaryState& bc_prev2, const VectorXd& x_prev,
                                const BoundaryState& bc_prev)
{
    std::tie(m_z2, m_z1) = m_autoencoder->encode_pair(x_prev2, x_prev);
    m_z = m_z1;
    m_p2 = boundary_params(bc_prev2);
    m_p1 = boundary_params(bc_prev);
    m_x = x_prev;
}

const VectorXd& LatentMlpIntegrator::boundary_params(const BoundaryState& bc)
{
    if (m_model.boundary.kind() == BoundaryInputKind::Velocity) return bc.params;
    m_p = m_model.boundary.of_frame(bc.params, bc.targets);
    return m_p;
}

void LatentMlpIntegrator::integrate_only(const BoundaryState& bc)
{
    const Index L = m_model.latent_dim, P = m_model.param_dim;
    m_input.segment(0, L) = m_z1.cast<float>();
    m_input.segment(L, L) = m_z2.cast<float>();
    m_input.segment(2 * L, P) = boundary_params(bc).cast<float>();
    m_input.segment(2 * L + P, P) = m_p1.cast<float>();
    m_input.segment(2 * L + 2 * P, P) = m_p2.cast<float>();
    const auto out = m_integrator_net.evaluate(m_input);
    m_z = m_z1 + (m_scale.cwiseProduct(out)).cast<double>();
}

void LatentMlpIntegrator::decode_only(const BoundaryState& bc)
{
    m_zf = m_z.cast<float>();  // preallocated: no allocation per frame
    const auto features = m_decoder_net.evaluate(m_zf);
    m_autoencoder->encoding().to_positions_into(features, bc.targets, m_x);
    if (m_model.overwrite_dirichlet) overwrite_dirichlet(m_autoencoder->encoding().bc_indices(), bc.targets, m_x);
}

StepTiming LatentMlpIntegrator::step(const BoundaryState& bc)
{
    StepTiming timing;
    Timer timer;
    integrate_only(bc);
    timing.integrate_seconds = timer.seconds();
    timer.reset();
    decode_only(bc);
    timing.decode_seconds = timer.seconds();
    m_z2.swap(m_z1);
    m_z1 = m_z;
    m_p2.swap(m_p1);
    m_p1 = m_model.boundary.kind() == BoundaryInputKind::Velocity ? bc.params : m_p;  // integrate_only's p_t
    return timing;
}

} // namespace lb
