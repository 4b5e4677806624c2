#pragma once
// method = "full_space": the reference simulator behind the Integrator interface
// (integrators/full_space_integrator.hpp): a full-space Newton solve per frame with the
// scene's solver settings. Nothing to fit, no options; the pipeline adds it to every
// scene when [evaluation] full_space = true.
#include "methods/method.hpp"

namespace lb {

MethodFactory full_space_method();

} // namespace lb
