#pragma once
// method = "fulton_cubature" and method = "fulton_full" (fulton_integrator.hpp).
// Options of both: penalty_weight, gradient_tolerance, max_evaluations, history_size,
// preconditioner_refresh.
// fulton_cubature also: tolerance, max_elements, candidates, max_poses, seed (cubature.hpp).
// Artefact: fulton_cubature the cubature (Cubature::save) and its accuracy on held-out
// reconstructions (attributes fulton.heldout_force_error, fulton.heldout_energy_error,
// fulton.heldout_poses); fulton_full a marker (nothing to fit; the autoencoder is the subspace).
#include "methods/method.hpp"

namespace lb {

MethodFactory fulton_cubature_method();
MethodFactory fulton_full_method();

} // namespace lb
