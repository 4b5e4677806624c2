#pragma once
// method = "linear_pca": Newton in a linear PCA subspace (linear_pca.hpp).
// Options: dim (default: the scene's latent size), penalty_weight, max_iterations,
// gradient_tolerance, step_tolerance. Artefact: the subspace (LinearPcaSubspace).
#include "methods/method.hpp"

namespace lb {

MethodFactory linear_pca_method();

} // namespace lb
