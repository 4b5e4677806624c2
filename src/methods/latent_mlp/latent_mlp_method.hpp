#pragma once
// method = "latent_mlp": the latent MLP integrator of Li et al. 2025 trained in the
// scene's autoencoder latent space (integrators/trainer.hpp), with
//   loss = "self_supervised" (the paper) or "supervised_l2" (the supervised baseline),
//   noise, balancing (the ablation switches),
// and the training keys of README "Experiment files" (hidden, epochs, batch,
// learning_rate, noise_fraction, balancing_floor, penalty_weight, seed, max_seconds).
// Artefact: the network under "integrator." (LatentMlpModel::save) plus epochs_run,
// final_loss and train_seconds attributes, and the loss per epoch (training_curve/integrator,
// nn/training_curve.hpp; its last value is final_loss).
#include "methods/method.hpp"

namespace lb {

MethodFactory latent_mlp_method();

} // namespace lb
