// tan_physics_mlp (Tan et al. §IV, §VI-A): the losses' gradients against finite
// differences of the losses with the stopped arguments frozen, the three stages on the
// small cloth, and a 1,500-frame rollout.
#include <gtest/gtest.h>

#include "baselines/builtin_methods.hpp"
#include "baselines/tan_physics_mlp/tan_training.hpp"
#include "core/error.hpp"
#include "eval/rollout.hpp"
#include "integrators/trainer.hpp"
#include "support/finite_difference.hpp"
#include "fulton_fixture.hpp"

namespace lb {
namespace {

using testing::FdOptions;
using testing::FultonProblem;

/// The small cloth, 90 frames, the first 70 for training, with a briefly trained autoencoder.
FultonProblem& cloth()
{
    static FultonProblem p("cloth", 90, 70, 150, 16, 12);
    return p;
}

/// Every entry of the parameters `params` (value references into a network).
struct Entries {
    std::vector<double*> value;
    std::vector<double*> grad;
};

Entries entries_of(std::vector<nn::ParameterRef> params, Index per_parameter)
{
    Entries e;
    for (nn::ParameterRef& p : params) {
        const Index n = p.value.size();
        const Index step = std::max<Index>(1, n / per_parameter);
        for (Index i = 0; i < n; i += step) {
            e.value.push_back(p.value.data() + i);
            e.grad.push_back(p.grad.data() + i);
        }
    }
    return e;
}

/// Central differences of `loss` with respect to the entries (restored afterwards).
VectorXd fd_gradient(const Entries& e, const std::function<double()>& loss, double step)
{
    VectorXd g(Index(e.value.size()));
    for (size_t k = 0; k < e.value.size(); ++k) {
        double& v = *e.value[k];
        const double v0 = v;
        v = v0 + step;
        const double plus = loss();
        v = v0 - step;
        const double minus = loss();
        v = v0;
        g[Index(k)] = (plus - minus) / (2.0 * step);
    }
    return g;
}

VectorXd analytic_gradient(const Entries& e)
{
    VectorXd g(Index(e.value.size()));
    for (size_t k = 0; k < e.grad.size(); ++k) g[Index(k)] = *e.grad[k];
    return g;
}

FdOptions fd_options(const VectorXd& analytic)
{
    FdOptions o;
    o.tol = 1e-4;
    o.scale = 1e-3 * analytic.cwiseAbs().maxCoeff();  // entries far below the largest are compared absolutely
    return o;
}

/// Columns of sequence 0's frames m + offset for the samples.
MatrixXd frames(const SequenceData& seq, const std::vector<TanSample>& batch, Index offset, bool targets)
{
    const MatrixXd& src = targets ? seq.bc_positions : seq.positions;
    MatrixXd out(src.cols(), Index(batch.size()));
    for (Index b = 0; b < out.cols(); ++b) out.col(b) = src.row(batch[size_t(b)].frame + offset).transpose();
    return out;
}

MatrixXd mlp_inputs(const SequenceData& seq, const MatrixXd& z1, const MatrixXd& z2,
                    const std::vector<TanSample>& batch, Index offset)
{
    MatrixXd in(2 * z1.rows() + 3 * seq.bc_params.cols(), z1.cols());
    for (Index b = 0; b < z1.cols(); ++b) {
        const Index m = batch[size_t(b)].frame + offset;
        in.col(b) = integrator_input(z1.col(b), z2.col(b), seq.bc_params.row(m).transpose(),
                                     seq.bc_params.row(m - 1).transpose(), seq.bc_params.row(m - 2).transpose());
    }
    return in;
}

LatentMlpModel small_mlp(FultonProblem& p, std::uint64_t seed)
{
    LatentMlpModel mlp = LatentMlpModel::create(p.ae->latent_dim(), p.data.sequences[0].bc_params.cols(), {8}, seed);
    fit_input_statistics(mlp, make_training_samples(*p.ae, p.data));
    return mlp;
}

/// Quiet options with the given widths and epochs per stage (other options at their defaults).
TanOptions stage_options(std::vector<Index> hidden, int epochs1, int epochs2, int epochs3)
{
    TanOptions o;
    o.progress = false;
    o.hidden = std::move(hidden);
    o.stage1_epochs = epochs1;
    o.stage2_epochs = epochs2;
    o.stage3_epochs = epochs3;
    return o;
}

constexpr double kPenalty = 1e5;

TEST(TanLosses, StoppedMphysGradientIsTheGradientWithTheFirstTwoArgumentsFrozen)
{
    FultonProblem& p = cloth();
    const SequenceData& seq = p.data.sequences[0];
    TanLosses losses(*p.model, p.data, *p.ae, kPenalty);
    LatentMlpModel mlp = small_mlp(p, 5);
    // A case where the two gradients must differ: an MLP fitted to the truth (L_sim only), so
    // the unrolled states are near the simulated ones, where ∇_x E(x_m; x_{m−1}, x_{m−2})
    // nearly vanishes (the truth minimises it) but the partials with respect to x_{m−1},
    // x_{m−2} — inertia, −2M(x_m − x̃)/h² and M(x_m − x̃)/h², the swinging cloth's
    // acceleration — do not: Tan's eq. 10 against eq. 9.
    {
        Autoencoder frozen_ae = *p.ae;
        TanOptions o = stage_options({8}, 0, 60, 0);
        o.window = 3;
        o.batch_size = 16;
        o.weights.mphys = 0.0;
        TanTrainer(*p.model, p.data, frozen_ae, o).stage2(mlp);
    }
    const std::vector<TanSample> batch{{0, 3}, {0, 30}};
    const Index K = 3, B = 2;
    TanWeights w;
    w.recon = w.ephys = w.sim = 0.0;
    w.mphys = 1.0;
    const Entries e = entries_of(mlp.network.parameters(), 12);

    mlp.network.zero_grad();
    const double loss0 = losses.mlp_loss(mlp, batch, K, w, true, true);
    const VectorXd stopped = analytic_gradient(e);
    mlp.network.zero_grad();
    losses.mlp_loss(mlp, batch, K, w, false, true);
    const VectorXd unstopped = analytic_gradient(e);

    // The loss with E's first two arguments frozen at the current weights' decoded states.
    LatentPotential potential(*p.model, *p.ae, kPenalty);
    std::vector<MatrixXd> frozen(size_t(K + 2));
    auto unrolled = [&](bool record) {
        std::vector<MatrixXd> Z(size_t(K + 2));
        Z[0] = p.ae->encode(frames(seq, batch, 0, false));
        Z[1] = p.ae->encode(frames(seq, batch, 1, false));
        if (record) {
            frozen[0] = p.ae->decode(Z[0], frames(seq, batch, 0, true));
            frozen[1] = p.ae->decode(Z[1], frames(seq, batch, 1, true));
        }
        double sum = 0.0;
        for (Index j = 2; j < K + 2; ++j) {
            const size_t u = size_t(j);
            Z[u] = mlp.forward(mlp_inputs(seq, Z[u - 1], Z[u - 2], batch, j), Z[u - 1], false);
            const MatrixXd T = frames(seq, batch, j, true);
            if (record) frozen[u] = p.ae->decode(Z[u], T);
            sum += potential.evaluate(Z[u], T, frozen[u - 1], frozen[u - 2]).energies.sum();
        }
        return losses.energy_scale() * sum / double(B * K);
    };
    EXPECT_NEAR(unrolled(true), loss0, 1e-10 * std::abs(loss0));
    const VectorXd fd_frozen = fd_gradient(e, [&] { return unrolled(false); }, 1e-6);
    EXPECT_TRUE(testing::matrices_close(stopped, fd_frozen, fd_options(stopped), "stopped L_mphys gradient"));

    // Without the stop the gradient is that of Tan's eq. 8 as written, and it must differ.
    const VectorXd fd_full = fd_gradient(e, [&] { return losses.mlp_loss(mlp, batch, K, w, false, false); }, 1e-6);
    EXPECT_TRUE(testing::matrices_close(unstopped, fd_full, fd_options(unstopped), "unstopped L_mphys gradient"));
    // They differ by more than either agrees with its finite differences, so each matches
    // only its own loss: the stop is not a no-op. (Relatively the difference is small here,
    // 0.15 % of the gradient: the decoded states' spurious elastic forces dominate both.)
    const double fd_error = std::max((stopped - fd_frozen).norm(), (unstopped - fd_full).norm());
    EXPECT_GT((stopped - unstopped).norm(), 20.0 * fd_error)
        << "|stopped - unstopped| " << (stopped - unstopped).norm() << ", finite-difference error " << fd_error;
    EXPECT_FALSE(testing::matrices_close(stopped, fd_full, fd_options(stopped), "stopped vs eq. 8"));
}

TEST(TanLosses, EphysGradientReachesDecoderAndEncoder)
{
    FultonProblem& p = cloth();
    Autoencoder ae = *p.ae;  // gradients accumulate into this copy only
    const SequenceData& seq = p.data.sequences[0];
    TanLosses losses(*p.model, p.data, ae, 1e5);
    const std::vector<TanSample> batch{{0, 4}, {0, 21}, {0, 55}};
    TanWeights w;
    w.recon = w.sim = w.mphys = 0.0;
    w.ephys = 1.0;
    std::vector<nn::ParameterRef> params = ae.encoder().parameters("encoder.");
    const Index encoder_params = Index(params.size());
    for (auto& q : ae.decoder().parameters("decoder.")) params.push_back(q);
    const Entries e = entries_of(params, 6);
    ae.encoder().zero_grad();
    ae.decoder().zero_grad();
    const double loss0 = losses.embedding_loss(batch, w, true);
    const VectorXd analytic = analytic_gradient(e);

    const MatrixXd T = frames(seq, batch, 0, true);
    const MatrixXd X1 = ae.decode(ae.encode(frames(seq, batch, -1, false)), frames(seq, batch, -1, true));
    const MatrixXd X2 = ae.decode(ae.encode(frames(seq, batch, -2, false)), frames(seq, batch, -2, true));
    LatentPotential potential(*p.model, ae, 1e5);
    auto frozen = [&] {
        const MatrixXd X = ae.decode(ae.encode(frames(seq, batch, 0, false)), T);
        return losses.energy_scale() * potential.evaluate_positions(X, T, X1, X2, {}).energies.sum() / 3.0;
    };
    EXPECT_NEAR(frozen(), loss0, 1e-10 * std::abs(loss0));
    const VectorXd fd = fd_gradient(e, frozen, 1e-6);
    EXPECT_TRUE(testing::matrices_close(analytic, fd, fd_options(analytic), "L_ephys gradient"));
    // Both networks receive a gradient.
    double encoder_norm = 0.0, decoder_norm = 0.0;
    for (size_t k = 0; k < params.size(); ++k)
        (Index(k) < encoder_params ? encoder_norm : decoder_norm) += params[k].grad.squaredNorm();
    EXPECT_GT(encoder_norm, 0.0);
    EXPECT_GT(decoder_norm, 0.0);
}

TEST(TanLosses, JointLossGradientMatchesFiniteDifferences)
{
    FultonProblem& p = cloth();
    Autoencoder ae = *p.ae;
    const SequenceData& seq = p.data.sequences[0];
    TanLosses losses(*p.model, p.data, ae, 1e5);
    LatentMlpModel mlp = small_mlp(p, 9);
    const std::vector<TanSample> batch{{0, 7}, {0, 40}};
    const TanWeights w;  // defaults: recon 1, ephys 0.5, sim 1
    std::vector<nn::ParameterRef> params = ae.encoder().parameters("encoder.");
    for (auto& q : ae.decoder().parameters("decoder.")) params.push_back(q);
    for (auto& q : mlp.network.parameters("integrator.")) params.push_back(q);
    const Entries e = entries_of(params, 5);
    ae.encoder().zero_grad();
    ae.decoder().zero_grad();
    mlp.network.zero_grad();
    const double loss0 = losses.joint_loss(mlp, batch, w, true);
    const VectorXd analytic = analytic_gradient(e);

    const MatrixXd T = frames(seq, batch, 0, true), X = frames(seq, batch, 0, false);
    const MatrixXd X1 = ae.decode(ae.encode(frames(seq, batch, -1, false)), frames(seq, batch, -1, true));
    const MatrixXd X2 = ae.decode(ae.encode(frames(seq, batch, -2, false)), frames(seq, batch, -2, true));
    LatentPotential potential(*p.model, ae, 1e5);
    auto frozen = [&] {
        const MatrixXd z = ae.encode(X), z1 = ae.encode(frames(seq, batch, -1, false)),
                       z2 = ae.encode(frames(seq, batch, -2, false));
        const MatrixXd z_mlp = mlp.forward(mlp_inputs(seq, z1, z2, batch, 0), z1, false);
        const MatrixXd X_hat = ae.decode(0.5 * z + 0.5 * z_mlp, T);
        const double recon = (X_hat - X).squaredNorm() / double(X.rows() * 2);
        const double ephys = losses.energy_scale() * potential.evaluate_positions(X_hat, T, X1, X2, {}).energies.sum() / 2.0;
        return w.recon * recon + w.ephys * ephys + w.sim * (z_mlp - z).squaredNorm() / 2.0;
    };
    EXPECT_NEAR(frozen(), loss0, 1e-10 * std::abs(loss0));
    const VectorXd fd = fd_gradient(e, frozen, 1e-6);
    EXPECT_TRUE(testing::matrices_close(analytic, fd, fd_options(analytic), "stage-3 loss gradient"));
}

TEST(TanStages, EachStageLowersItsOwnLossOnTheSmallCloth)
{
    FultonProblem& p = cloth();
    Autoencoder ae = *p.ae;
    TanOptions o = stage_options({16, 16}, 20, 40, 20);
    o.window = 5;
    o.batch_size = 32;
    TanTrainer trainer(*p.model, p.data, ae, o);
    const FrameSet train = training_frames(p.data);
    LatentMlpModel mlp = LatentMlpModel::create(ae.latent_dim(), p.data.sequences[0].bc_params.cols(), o.hidden, 0);

    const TanStageReport s1 = trainer.stage1();
    EXPECT_LT(s1.loss_after, s1.loss_before);
    const double rmse_stage1 = ae.relative_rmse(train.positions, train.bc_targets);
    const TanStageReport s2 = trainer.stage2(mlp);
    EXPECT_LT(s2.loss_after, s2.loss_before);
    const TanStageReport s3 = trainer.stage3(mlp);
    EXPECT_LT(s3.loss_after, s3.loss_before);
    // Stage 3 fine-tunes the embedding with the MLP in the loop: its plain reconstruction
    // error D(E(x)) may grow, but by at most 2× stage 1's.
    const double rmse_stage3 = ae.relative_rmse(train.positions, train.bc_targets);
    EXPECT_LE(rmse_stage3, 2.0 * rmse_stage1) << "stage 1 " << rmse_stage1 << ", stage 3 " << rmse_stage3;
    RecordProperty("relative_rmse_stage1", std::to_string(rmse_stage1));
    RecordProperty("relative_rmse_stage3", std::to_string(rmse_stage3));
}

TEST(TanStages, SmallClothRolloutOf1500FramesStaysFinite)
{
    // The whole small-cloth sequence, its first 300 frames for training (as the scene says).
    FultonProblem p("cloth", 1500, 300, 300, 32, 50);
    const SequenceData& seq = p.data.sequences.front();
    ASSERT_EQ(seq.num_frames(), 1500);
    const PhysicsModel& model = *p.model;
    Autoencoder& ae = *p.ae;
    const TanOptions o = stage_options({32, 32}, 20, 60, 10);
    TanTrainer trainer(model, p.data, ae, o);
    LatentMlpModel mlp = LatentMlpModel::create(ae.latent_dim(), seq.bc_params.cols(), o.hidden, 0);
    trainer.stage1();
    trainer.stage2(mlp);
    trainer.stage3(mlp);
    LatentMlpIntegrator integrator("tan_physics_mlp", std::make_shared<Autoencoder>(ae), std::move(mlp));
    const RolloutResult r = rollout(integrator, model, seq);
    EXPECT_TRUE(r.positions.allFinite()) << "non-finite state in the 1,500-frame rollout";
    // The horizon is reported, not asserted: blow-up is RMSE > 0.5 of the diagonal.
    RecordProperty("stable_horizon", r.summary.stable_horizon);
    RecordProperty("horizon_loose", r.summary.horizon_loose);
    std::printf("tan_physics_mlp small cloth: stable horizon %d of %ld frames, first RMSE > 0.1 at %d, test mean "
                "RMSE %.4g\n",
                r.summary.stable_horizon, long(seq.num_frames()), r.summary.horizon_loose, r.summary.test.mean_rmse);
}

TEST(TanMethod, OptionsAreRangeChecked)
{
    const MethodRegistry& r = builtin_methods();
    EXPECT_NO_THROW(r.parse_text("tan_physics_mlp", "stage1 = false\nstage3 = false\n", "test"));
    for (const char* bad : {"window = 0\n", "window = 1001\n", "lambda_ephys = -0.5\n", "lambda_mphys = nan\n",
                            "stage2 = false\nstage3 = false\n", "lambda_sim = 0.0\nlambda_mphys = 0.0\n",
                            "batch = 0\n", "stage2_epochs = -1\n", "learning_rate = 0.0\n",
                            "ae_learning_rate = -1.0\n", "penalty_weight = 0.0\n", "max_seconds = -1.0\n",
                            "seed = -1\n", "hidden = [0]\n"}) {
        EXPECT_THROW(r.parse_text("tan_physics_mlp", bad, "test"), ConfigError) << bad;
    }
}

} // namespace
} // namespace lb
