#include "methods/artefact.hpp"

#include "core/error.hpp"
#include "io/hdf5.hpp"

namespace lb {

namespace {
constexpr const char* kArtefactFormat = "latentbench.method/1";
}

void fit_artefact(const Method& method, const MethodInputs& inputs, const std::string& scene_name,
                  const std::string& path, const std::string& config_text)
{
    h5::write_file_atomically(path, [&](h5::File& f) {
        method.fit(inputs, f);
        f.set_attribute("/", "format", std::string(kArtefactFormat));
        f.set_attribute("/", "method", method.method_name());
        f.set_attribute("/", "method_options", method.options_text());
        f.set_attribute("/", "scene", scene_name);
        f.set_attribute("/", "config", config_text);
    });
}

bool is_artefact(const h5::File& file)
{
    return file.has_attribute("/", "format") && file.attribute_string("/", "format") == kArtefactFormat;
}

ArtefactInfo read_artefact_info(const h5::File& file)
{
    if (!is_artefact(file))
        throw IoError("'" + file.path() + "' is not a method artefact (no format attribute '" +
                      std::string(kArtefactFormat) + "'; make one with `latentbench fit`)");
    ArtefactInfo info;
    info.method = file.attribute_string("/", "method");
    info.options = file.attribute_string("/", "method_options");
    info.scene = file.attribute_string("/", "scene");
    return info;
}

std::unique_ptr<Method> method_from_artefact(const MethodRegistry& registry, const h5::File& file)
{
    const ArtefactInfo info = read_artefact_info(file);
    if (!registry.find(info.method))
        throw IoError("'" + file.path() + "' was made by method '" + info.method +
                      "', which this build does not have (known: " + registry.names() + ")");
    try {
        return registry.parse_text(info.method, info.options, file.path() + " (method_options)");
    } catch (const ConfigError& e) {
        throw IoError(std::string("'") + file.path() + "': stored method options are invalid: " + e.what());
    }
}

} // namespace lb
