#include "example_method.hpp"

#include "io/hdf5.hpp"
#include "sim/dataset.hpp"

namespace lb::example {

namespace {

// 1. The integrator: the reset/step protocol of integrators/integrator.hpp.
class ConstantVelocity final : public Integrator {
public:
    ConstantVelocity(std::string name, std::vector<int> bc, double damping)
        : m_name(std::move(name)), m_bc(std::move(bc)), m_damping(damping)
    {
    }
    std::string name() const override { return m_name; }
    void reset(const VectorXd& x_prev2, const BoundaryState&, const VectorXd& x_prev, const BoundaryState&) override
    {
        m_prev2 = x_prev2;
        m_prev = x_prev;
        m_x = x_prev;
    }
    StepTiming step(const BoundaryState& bc) override
    {
        m_x = m_prev + m_damping * (m_prev - m_prev2);
        for (size_t k = 0; k < m_bc.size(); ++k) m_x.segment<3>(3 * m_bc[k]) = bc.targets.segment<3>(3 * Index(k));
        m_prev2.swap(m_prev);
        m_prev = m_x;
        return {};
    }
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_empty; }

private:
    std::string m_name;
    std::vector<int> m_bc;
    double m_damping;
    VectorXd m_prev, m_prev2, m_x, m_empty;
};

// 2. The method: options, fit (artefact) and load.
class ConstantVelocityMethod final : public Method {
public:
    explicit ConstantVelocityMethod(double damping) : m_damping(damping) { }
    std::string method_name() const override { return "constant_velocity"; }
    void resolve(const MethodScene&) override { }
    std::string options_text() const override
    {
        toml::table t;
        t.insert_or_assign("damping", m_damping);
        return to_toml_string(t);
    }
    std::string summary() const override { return "x_t = x_{t-1} + " + std::to_string(m_damping) + " (x_{t-1} - x_{t-2})"; }
    void fit(const MethodInputs& in, h5::File& out) const override
    {
        const SequenceData& s = in.data->sequences.front();
        const MatrixXd v = s.positions.bottomRows(s.train_frames - 1) - s.positions.topRows(s.train_frames - 1);
        out.set_attribute("/", "mean_step", v.cwiseAbs().mean());
    }
    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File*, const std::string& label) const override
    {
        return std::make_unique<ConstantVelocity>(label, in.data->physics.bc_indices, m_damping);
    }

private:
    double m_damping;
};

} // namespace

// 3. The factory: the name in experiment files and how options are read.
MethodFactory constant_velocity_method()
{
    MethodFactory f;
    f.name = "constant_velocity";
    f.description = "example: constant-velocity extrapolation (README, Adding an integrator)";
    f.parse = [](ConfigTable& entry, ConfigTable&) -> std::unique_ptr<Method> {
        const double damping = entry.get_double("damping", 1.0);
        if (!(damping >= 0.0 && damping <= 1.0)) entry.fail("damping", "must lie in [0, 1]");
        entry.finish();
        return std::make_unique<ConstantVelocityMethod>(damping);
    };
    return f;
}

} // namespace lb::example
