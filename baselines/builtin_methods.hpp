#pragma once
// Every method this build knows: the core library's (latent_mlp, full_space) and the
// baselines'. A new method is one folder plus one line in builtin_methods.cpp.
#include "methods/registry.hpp"

namespace lb {

/// The registry of built-in methods, filled on first use.
const MethodRegistry& builtin_methods();

} // namespace lb
