#include "baselines/linear_pca/linear_pca_method.hpp"

#include <cstdio>

#include "baselines/linear_pca/linear_pca.hpp"
#include "io/hdf5.hpp"

namespace lb {

namespace {

class LinearPcaMethod final : public Method {
public:
    explicit LinearPcaMethod(LinearPcaOptions options) : m_options(options) { }

    std::string method_name() const override { return "linear_pca"; }
    void resolve(const MethodScene& scene) override
    {
        if (m_options.dim == 0) m_options.dim = scene.latent_dim;
    }
    std::string options_text() const override
    {
        toml::table t;
        t.insert_or_assign("dim", (long long)m_options.dim);
        t.insert_or_assign("penalty_weight", m_options.penalty_weight);
        t.insert_or_assign("max_iterations", (long long)m_options.max_iterations);
        t.insert_or_assign("gradient_tolerance", m_options.gradient_tolerance);
        t.insert_or_assign("step_tolerance", m_options.step_tolerance);
        return to_toml_string(t);
    }
    std::string summary() const override { return "linear PCA, d = " + std::to_string(m_options.dim); }

    void fit(const MethodInputs& in, h5::File& out) const override
    {
        LinearPcaSubspace::fit(*in.data, m_options.dim).save(out);
    }

    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File* artefact,
                                     const std::string& label) const override
    {
        return std::make_unique<LinearPcaIntegrator>(label, *in.model, LinearPcaSubspace::load(*artefact, in.data->physics),
                                                     m_options);
    }

    std::string after_rollout(const Integrator& integrator) const override
    {
        const auto& pca = static_cast<const LinearPcaIntegrator&>(integrator);
        char line[160];
        std::snprintf(line, sizeof line, "%.2f reduced Newton iterations per step, %d solves stopped before converging",
                      pca.mean_iterations(), pca.unconverged_steps());
        return line;
    }

private:
    LinearPcaOptions m_options;
};

std::unique_ptr<Method> parse_linear_pca(ConfigTable& entry, ConfigTable&)
{
    LinearPcaOptions o;
    o.dim = Index(entry.get_int("dim", 0, 0, kMaxWidth));
    o.penalty_weight = entry.get_double("penalty_weight", o.penalty_weight);
    o.max_iterations = entry.get_count("max_iterations", o.max_iterations, 1, 1'000'000);
    o.gradient_tolerance = entry.get_double("gradient_tolerance", o.gradient_tolerance);
    o.step_tolerance = entry.get_double("step_tolerance", o.step_tolerance);
    if (o.dim < 0) entry.fail("dim", "must be positive (or omitted: the scene's latent size)");
    if (!(o.penalty_weight > 0.0)) entry.fail("penalty_weight", "must be positive");
    if (o.max_iterations < 1) entry.fail("max_iterations", "must be at least 1");
    if (!(o.gradient_tolerance > 0.0)) entry.fail("gradient_tolerance", "must be positive");
    if (!(o.step_tolerance >= 0.0)) entry.fail("step_tolerance", "must be non-negative");
    entry.finish();
    return std::make_unique<LinearPcaMethod>(o);
}

} // namespace

MethodFactory linear_pca_method()
{
    MethodFactory f;
    f.name = "linear_pca";
    f.description = "baseline: Newton on the full-space incremental potential in a linear PCA subspace of the training frames";
    f.parse = parse_linear_pca;
    return f;
}

} // namespace lb
