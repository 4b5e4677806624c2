#include "methods/full_space/full_space_method.hpp"

#include "integrators/full_space_integrator.hpp"

namespace lb {

namespace {

class FullSpaceMethod final : public Method {
public:
    std::string method_name() const override { return "full_space"; }
    void resolve(const MethodScene&) override { }
    std::string options_text() const override { return ""; }
    std::string summary() const override { return "reference simulator"; }
    bool has_artefact() const override { return false; }
    void fit(const MethodInputs&, h5::File&) const override { }
    std::unique_ptr<Integrator> load(const MethodInputs& in, const h5::File*, const std::string&) const override
    {
        return std::make_unique<FullSpaceIntegrator>(*in.model, in.newton);
    }
};

} // namespace

MethodFactory full_space_method()
{
    MethodFactory f;
    f.name = "full_space";
    f.description = "the reference: a full-space Newton solve of the incremental potential per frame";
    f.parse = [](ConfigTable& entry, ConfigTable&) -> std::unique_ptr<Method> {
        entry.finish();
        return std::make_unique<FullSpaceMethod>();
    };
    return f;
}

} // namespace lb
