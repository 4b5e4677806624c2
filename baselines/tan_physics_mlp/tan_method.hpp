#pragma once
// method = "tan_physics_mlp": Tan, Pan, Gao & Manocha's physics-loss feature-space simulator
// z_m = MLP(z_{m−2}, z_{m−1}, q_m) on its own copy of the scene's autoencoder, trained in
// the three stages of their §VI-A (tan_training.hpp; losses tan_losses.hpp).
//
// Options (all optional; ranges checked, unknown keys rejected by name):
//   stage1, stage2, stage3      bool, each stage on/off (stage2 or stage3 must be on)
//   lambda_recon, lambda_ephys, lambda_sim, lambda_mphys   ≥ 0 (1, 0.5, 1, 0.5)
//   window                      K, unrolled steps of L_mphys [1, 1000] (10)
//   stop_gradient               bool (true: Tan eq. 11)
//   hidden                      MLP widths (default: the scene's integrator widths, paper Table 2)
//   stage1_epochs, stage2_epochs, stage3_epochs   [0, 10⁷] (100, 300, 50)
//   batch                       frames / windows per batch [1, 10⁷] (64)
//   learning_rate               stage 2 (1e-3);  ae_learning_rate  stages 1, 3 (1e-5)
//   penalty_weight              w_bc > 0 (1e5);  seed ≥ 0;  max_seconds ≥ 0 (per stage, 0: none)
// Artefact: the fine-tuned autoencoder ("tan_ae." prefix, Autoencoder::save_into), the MLP
// ("integrator.", LatentMlpModel::save), per stage tan.stage<k>.{ran, loss_before, loss_after,
// recon, ephys, sim, mphys (after), epochs, seconds}, the budget attributes of every learned
// method, the loss per epoch of each stage that ran (training_curve/stage<k>,
// nn/training_curve.hpp) with final_loss the last stage's last loss, and the embedding metrics (eval/embedding_metrics.hpp) of the shared autoencoder,
// of its own after stage 1 and of its own at the end.
#include "methods/method.hpp"

namespace lb {

MethodFactory tan_physics_mlp_method();

} // namespace lb
