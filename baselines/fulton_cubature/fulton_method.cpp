#include "baselines/fulton_cubature/fulton_method.hpp"

#include <cstdio>
#include <limits>

#include "baselines/fulton_cubature/fulton_integrator.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "io/hdf5.hpp"

namespace lb {

namespace {

constexpr const char* kFullFormat = "latentbench.fulton_full/1";
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Reconstructions decode(encode(x)) of frames [begin, end) of every sequence (3N × S).
MatrixXd reconstructions(Autoencoder& ae, const Dataset& data, bool training)
{
    std::vector<std::pair<const SequenceData*, Index>> frames;
    for (const SequenceData& seq : data.sequences) {
        const Index begin = training ? 0 : seq.train_frames;
        const Index end = training ? std::min<Index>(seq.train_frames, seq.num_frames()) : seq.num_frames();
        for (Index t = begin; t < end; ++t) frames.push_back({&seq, t});
    }
    const Index n = Index(frames.size());
    if (n == 0) return MatrixXd(data.physics.mesh.num_vertices() * 3, 0);
    MatrixXd X(frames.front().first->positions.cols(), n), T(frames.front().first->bc_positions.cols(), n);
    for (Index j = 0; j < n; ++j) {
        X.col(j) = frames[size_t(j)].first->positions.row(frames[size_t(j)].second).transpose();
        T.col(j) = frames[size_t(j)].first->bc_positions.row(frames[size_t(j)].second).transpose();
    }
    return ae.decode(ae.encode(X), T);
}

/// Every k-th column, k chosen so at most `count` remain.
MatrixXd thinned(const MatrixXd& X, Index count)
{
    if (X.cols() <= count) return X;
    const Index stride = (X.cols() + count - 1) / count;
    MatrixXd out(X.rows(), (X.cols() + stride - 1) / stride);
    for (Index j = 0; j < out.cols(); ++j) out.col(j) = X.col(j * stride);
    return out;
}

class FultonMethod final : public Method {
public:
    FultonMethod(bool cubature, FultonOptions options, CubatureOptions cubature_options)
        : m_cubature(cubature), m_options(options), m_cubature_options(cubature_options)
    {
    }

    std::string method_name() const override { return m_cubature ? "fulton_cubature" : "fulton_full"; }
    void resolve(const MethodScene&) override { }
    std::string options_text() const override
    {
        toml::table t;
        t.insert_or_assign("penalty_weight", m_options.penalty_weight);
        t.insert_or_assign("gradient_tolerance", m_options.gradient_tolerance);
        t.insert_or_assign("max_evaluations", (long long)m_options.max_evaluations);
        t.insert_or_assign("history_size", (long long)m_options.history_size);
        t.insert_or_assign("preconditioner_refresh", (long long)m_options.preconditioner_refresh);
        if (m_cubature) {
            t.insert_or_assign("tolerance", m_cubature_options.tolerance);
            t.insert_or_assign("max_elements", (long long)m_cubature_options.max_elements);
            t.insert_or_assign("candidates", (long long)m_cubature_options.candidates);
            t.insert_or_assign("max_poses", (long long)m_cubature_options.max_poses);
            t.insert_or_assign("seed", (long long)m_cubature_options.seed);
        }
        return to_toml_string(t);
    }
    std::string summary() const override
    {
        if (!m_cubature) return "latent L-BFGS, exact elastic energy";
        char line[120];
        std::snprintf(line, sizeof line, "latent L-BFGS, cubature to %g force error (≤ %d elements)",
                      m_cubature_options.tolerance, m_cubature_options.max_elements);
        return line;
    }
    bool needs_autoencoder() const override { return true; }

    void fit(const MethodInputs& in, h5::File& out) const override
    {
        if (!m_cubature) {
            out.set_attribute("/", "fulton.format", std::string(kFullFormat));
            return;
        }
        Autoencoder& ae = *in.autoencoder;
        const PcaSplitDecoder split(ae, *in.model);
        const MatrixXd train = reconstructions(ae, *in.data, true);
        const Cubature cubature = train_cubature(*in.model, split, train, m_cubature_options);
        // Held out: reconstructions of the test window (frames ≥ train_frames) if there are any.
        const MatrixXd heldout = thinned(reconstructions(ae, *in.data, false), m_cubature_options.max_poses);
        const CubatureAccuracy acc =
            heldout.cols() > 0 ? cubature_accuracy(*in.model, split, cubature, heldout) : CubatureAccuracy{kNaN, kNaN};
        log_info("fulton_cubature: %zu elements, training force error %.4f (stopped: %s), held-out force error %.4f, "
                 "energy error %.4f on %ld poses, %.2f s",
                 cubature.elements.size(), cubature.training_error, cubature.stop_reason.c_str(), acc.force_error,
                 acc.energy_error, long(heldout.cols()), cubature.seconds);
        cubature.save(out);
        out.set_attribute("/", "fulton.heldout_force_error", acc.force_error);
        out.set_attribute("/", "fulton.heldout_energy_error", acc.energy_error);
        out.set_attribute("/", "fulton.heldout_poses", (long long)heldout.cols());
    }

    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        std::optional<Cubature> cubature;
        if (m_cubature) {
            cubature = Cubature::load(*artefact, *in.model);
        } else if (!artefact->has_attribute("/", "fulton.format") ||
                   artefact->attribute_string("/", "fulton.format") != kFullFormat) {
            throw IoError(artefact->path() + ": is not a fulton_full artefact (attribute fulton.format)");
        }
        return std::make_unique<FultonIntegrator>(label, in.autoencoder, *in.model, std::move(cubature), m_options);
    }

    std::string after_rollout(const Integrator& integrator) const override
    {
        const auto& f = static_cast<const FultonIntegrator&>(integrator);
        char line[200];
        std::snprintf(line, sizeof line,
                      "%.2f L-BFGS iterations and %.2f evaluations per step, %ld vertices decoded per evaluation, %d of "
                      "%zu step solves stopped before converging",
                      f.mean_iterations(), f.mean_evaluations(), long(f.decoded_vertices()), f.unconverged_steps(),
                      f.summaries().size());
        return line;
    }

private:
    bool m_cubature;
    FultonOptions m_options;
    CubatureOptions m_cubature_options;
};

std::unique_ptr<Method> parse_fulton(ConfigTable& entry, bool cubature)
{
    FultonOptions o;
    o.penalty_weight = entry.get_double("penalty_weight", o.penalty_weight);
    o.gradient_tolerance = entry.get_double("gradient_tolerance", o.gradient_tolerance);
    o.max_evaluations = entry.get_count("max_evaluations", o.max_evaluations, 1, 1'000'000);
    o.history_size = entry.get_count("history_size", o.history_size, 1, 1'000);
    o.preconditioner_refresh = entry.get_count("preconditioner_refresh", o.preconditioner_refresh, 0, 1'000'000);
    if (!(o.penalty_weight > 0.0)) entry.fail("penalty_weight", "must be positive");
    if (!(o.gradient_tolerance > 0.0)) entry.fail("gradient_tolerance", "must be positive");
    CubatureOptions c;
    if (cubature) {
        c.tolerance = entry.get_double("tolerance", c.tolerance);
        c.max_elements = entry.get_count("max_elements", c.max_elements, 1, 10'000'000);
        c.candidates = entry.get_count("candidates", c.candidates, 1, 10'000'000);
        c.max_poses = entry.get_count("max_poses", c.max_poses, 1, 10'000'000);
        const long long seed = entry.get_int("seed", 0, 0, kMaxSeed);
        if (!(c.tolerance > 0.0 && c.tolerance < 1.0)) entry.fail("tolerance", "must lie in (0, 1)");
        c.seed = std::uint64_t(seed);
    }
    entry.finish();
    return std::make_unique<FultonMethod>(cubature, o, c);
}

} // namespace

MethodFactory fulton_cubature_method()
{
    MethodFactory f;
    f.name = "fulton_cubature";
    f.description = "baseline (Fulton et al. 2019): per step, L-BFGS on the incremental potential over the latent, "
                    "elastic energy by cubature (An et al. 2008), gradients by one VJP through the decoder";
    f.parse = [](ConfigTable& entry, ConfigTable&) { return parse_fulton(entry, true); };
    f.quick_options = "max_elements = 40\ncandidates = 100\nmax_poses = 40\n";
    return f;
}

MethodFactory fulton_full_method()
{
    MethodFactory f;
    f.name = "fulton_full";
    f.description = "oracle of fulton_cubature: the same latent L-BFGS step with the exact full-space elastic energy";
    f.parse = [](ConfigTable& entry, ConfigTable&) { return parse_fulton(entry, false); };
    f.quick_options = "";
    return f;
}

} // namespace lb
