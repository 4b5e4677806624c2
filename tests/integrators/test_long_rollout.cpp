// Issue-4 acceptance at test scale: a self-supervised integrator (noise and
// balancing on) trained on the first frames of the small cantilever and small
// cloth rolls out at least 1,000 frames (≥ 3× the training horizon) without a
// non-finite state and with the Dirichlet vertices within a stated bound.
#include "paper/scene_defaults.hpp"
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include "core/log.hpp"
#include "eval/rollout.hpp"
#include "integrators/trainer.hpp"

namespace lb {
namespace {

struct Case {
    const char* scene;
    /// Bound on max_{t,i∈B} |x_i − x*_i| relative to the bounding-box diagonal: 2%, a
    /// fifth of the stable-horizon threshold. Cloth and solids hold the boundary only
    /// through the penalty (w_bc = 1e5) of the loss. The cantilever's largest violation is
    /// a transient in the first three predicted frames (the release from rest, the frames
    /// its 4-dimensional autoencoder reconstructs worst); measured on an AMD EPYC
    /// (AVX-512), autoencoder and integrator seeds 0, 1, 2: 0.48%, 1.8%, 0.80% (test
    /// window 0.06–0.24%); cloth 0.02%.
    double max_bc_violation;
};

class LongRollout : public ::testing::TestWithParam<Case> { };

TEST_P(LongRollout, SelfSupervisedStaysStableAndOnTheBoundary)
{
    set_log_level(LogLevel::Quiet);
    const Case c = GetParam();
    const Scene scene = load_scene(std::string(LB_SOURCE_DIR) + "/experiments/scenes/" + c.scene + ".toml", {"small"});
    SimulateOptions so;
    so.progress = false;
    const Dataset data = simulate_scene(scene, so);
    const SequenceData& seq = data.sequences.front();
    ASSERT_GE(seq.num_frames(), 1000);
    ASSERT_GE(seq.num_frames(), 3 * seq.train_frames);
    const PhysicsModel model(data.physics);

    AutoencoderOptions ao;
    ao.latent_dim = 4;
    ao.hidden = {64, 64};
    ao.epochs = 800;
    ao.batch_size = 64;
    ao.learning_rate = 1e-3;
    ao.progress = false;
    // All 800 epochs: early stopping on the 10 validation frames (every 10th training frame)
    // stopped seeds 0 and 1 early on that machine, and their release transient then reached
    // 6.7% and 7.2% of the diagonal (the same code had measured 1.0% on another CPU).
    ao.patience = 0;
    auto ae = std::make_shared<Autoencoder>(data.physics, ao, 0);
    train_autoencoder(*ae, data, ao);

    IntegratorTrainOptions o;
    o.hidden = default_integrator_hidden(scene.name);
    o.epochs = 1500;
    o.learning_rate = 1e-3;
    o.progress = false;
    const TrainingSamples samples = make_training_samples(*ae, data);
    LatentMlpModel net = LatentMlpModel::create(ae->latent_dim(), samples.p.rows(), o.hidden, 0);
    IntegratorTrainer(model, *ae, o).train(net, samples);

    LatentMlpIntegrator integrator("ours", ae, std::move(net));
    const RolloutResult r = rollout(integrator, model, seq);
    EXPECT_TRUE(r.positions.allFinite()) << c.scene << ": non-finite state in the rollout";
    EXPECT_EQ(r.summary.stable_horizon, seq.num_frames()) << c.scene;
    const double max_bc = std::max(r.summary.train.max_bc_violation, r.summary.test.max_bc_violation);
    EXPECT_LE(max_bc, c.max_bc_violation * model.length_scale())
        << c.scene << ": max boundary violation " << max_bc << " m";
    log_info("%s: %d frames, stable %d, final RMSE %.4f, max BC violation %.3g m", c.scene, r.summary.frames,
             r.summary.stable_horizon, r.summary.test.final_rmse, max_bc);
}

INSTANTIATE_TEST_SUITE_P(SmallScenes, LongRollout,
                         ::testing::Values(Case{"cantilever", 0.02}, Case{"cloth", 0.02}),
                         [](const auto& info) { return std::string(info.param.scene); });

} // namespace
} // namespace lb
