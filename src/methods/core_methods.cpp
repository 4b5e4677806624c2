#include "methods/full_space/full_space_method.hpp"
#include "methods/latent_mlp/latent_mlp_method.hpp"
#include "methods/registry.hpp"

namespace lb {

void register_core_methods(MethodRegistry& registry)
{
    registry.add(latent_mlp_method());
    registry.add(full_space_method());
}

} // namespace lb
