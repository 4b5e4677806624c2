#pragma once
// The methods a build knows, by name. The library in src/ registers its own
// (latent_mlp, full_space; src/methods/core_methods.cpp); baselines/ and a user's
// methods are added in baselines/builtin_methods.cpp, which links above src/.
#include <string>
#include <vector>

#include "methods/method.hpp"

namespace lb {

class MethodRegistry {
public:
    /// @throws Error if a method of that name is registered already
    void add(MethodFactory factory);
    /// nullptr if unknown
    const MethodFactory* find(const std::string& name) const;
    /// @throws ConfigError naming the method and listing the known ones
    const MethodFactory& get(const std::string& name) const;
    const std::vector<MethodFactory>& all() const { return m_factories; }
    /// "full_space, latent_mlp, linear_pca"
    std::string names() const;

    /// Parse an [[integrators]]-style table: `method` (default "latent_mlp") picks the
    /// factory, the rest are the method's options over `defaults`.
    std::unique_ptr<Method> parse(ConfigTable& entry, ConfigTable& defaults) const;
    /// The same from TOML text (an artefact's stored options or `fit --set` pairs).
    std::unique_ptr<Method> parse_text(const std::string& method, const std::string& options_toml,
                                       const std::string& source) const;

private:
    std::vector<MethodFactory> m_factories;
};

/// Adds the methods of the core library: latent_mlp (the paper's integrator and its
/// supervised L2 baseline, by `loss`) and full_space (the reference simulator).
void register_core_methods(MethodRegistry& registry);

} // namespace lb
