#pragma once
// A method's artefact: the HDF5 file its fit() writes, marked with what made it, so
// that `rollout` and the pipeline can rebuild the method from the file alone:
//   attributes  format = "latentbench.method/1", method (registered name),
//               method_options (the resolved options, TOML), scene, config (what ran it)
//   datasets    whatever the method writes.
#include <memory>
#include <string>

#include "methods/registry.hpp"

namespace lb {

namespace h5 {
class File;
}

struct ArtefactInfo {
    std::string method;
    std::string options;  ///< TOML
    std::string scene;
};

/// Run method.fit() into `path`, written atomically (nothing is left on failure).
/// @param config_text  the configuration that asked for it (embedded as provenance)
void fit_artefact(const Method& method, const MethodInputs& inputs, const std::string& scene_name,
                  const std::string& path, const std::string& config_text);

/// True if `file` carries the artefact attributes.
bool is_artefact(const h5::File& file);
/// IoError naming the file if it is not an artefact.
ArtefactInfo read_artefact_info(const h5::File& file);
/// The method that made the artefact, with its stored options (resolved already).
std::unique_ptr<Method> method_from_artefact(const MethodRegistry& registry, const h5::File& file);

} // namespace lb
