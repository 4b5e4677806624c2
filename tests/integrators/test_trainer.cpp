#include <gtest/gtest.h>

#include <filesystem>
#include <numeric>

#include "core/error.hpp"
#include "integrators/integrator_fixture.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using testing::TinyProblem;

std::vector<Index> all_indices(Index n)
{
    std::vector<Index> idx(static_cast<size_t>(n));
    std::iota(idx.begin(), idx.end(), 0);
    return idx;
}

/// Fit standardiser/scale as train() does, without training.
void prepare(LatentMlpModel& net, const TrainingSamples& s)
{
    MatrixXd inputs(net.input_dim(), s.size());
    inputs << s.z_prev, s.z_prev2, s.p, s.p_prev, s.p_prev2;
    net.inputs = nn::Standardizer::fit(inputs);
    net.output_scale = VectorXd::Constant(net.latent_dim, 0.1);
}

struct LossCase {
    IntegratorLoss loss;
    bool overwrite_dirichlet;
};

class LossGradient : public ::testing::TestWithParam<LossCase> { };

// ∂L/∂θ of the integrator weights (through the decoder, the energy and the
// balancing weights) against central finite differences of the loss; also with the
// decoded Dirichlet vertices overwritten (the cantilever has a penalty, so it matters).
TEST_P(LossGradient, MatchesFiniteDifferences)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    o.loss = GetParam().loss;
    o.overwrite_dirichlet = GetParam().overwrite_dirichlet;
    o.hidden = {8, 8};
    o.training_noise = true;
    o.data_balancing = true;
    IntegratorTrainer trainer(*p.model, *p.ae, o);
    trainer.set_velocity_floor(1e-3);
    LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    prepare(net, p.samples);
    Rng rng(11);
    std::vector<Index> idx = all_indices(std::min<Index>(p.samples.size(), 6));
    const IntegratorBatch batch = trainer.make_batch(p.samples, idx, rng);

    auto params = net.network.parameters();
    net.network.zero_grad();
    trainer.loss_and_gradient(net, batch);
    // Check a spread of entries of every parameter tensor.
    std::vector<std::pair<size_t, Index>> entries;
    for (size_t k = 0; k < params.size(); ++k) {
        for (Index j = 0; j < params[k].value.size(); j += std::max<Index>(1, params[k].value.size() / 5)) {
            entries.push_back({k, j});
        }
    }
    VectorXd theta(Index(entries.size())), analytic(Index(entries.size()));
    for (size_t e = 0; e < entries.size(); ++e) {
        theta[Index(e)] = params[entries[e].first].value.data()[entries[e].second];
        analytic[Index(e)] = params[entries[e].first].grad.data()[entries[e].second];
    }
    auto f = [&](const VectorXd& th) {
        for (size_t e = 0; e < entries.size(); ++e) params[entries[e].first].value.data()[entries[e].second] = th[Index(e)];
        const double value = trainer.loss(net, batch);
        for (size_t e = 0; e < entries.size(); ++e) params[entries[e].first].value.data()[entries[e].second] = theta[Index(e)];
        return value;
    };
    testing::FdOptions fd;
    fd.step = 1e-6;
    fd.tol = 2e-4;
    fd.scale = 1e-6 * analytic.cwiseAbs().maxCoeff();
    EXPECT_TRUE(testing::check_gradient(f, [&](const VectorXd&) { return analytic; }, theta, fd, "dL/dtheta"));
    EXPECT_GT(analytic.cwiseAbs().maxCoeff(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Losses, LossGradient,
                         ::testing::Values(LossCase{IntegratorLoss::SelfSupervised, false},
                                           LossCase{IntegratorLoss::SupervisedL2, false},
                                           LossCase{IntegratorLoss::SelfSupervised, true}),
                         [](const auto& info) {
                             return to_string(info.param.loss) +
                                    (info.param.overwrite_dirichlet ? "_overwrite_dirichlet" : "");
                         });

// The representation switches of issue 14 enter the fingerprint only when not the paper's,
// so checkpoints and fits made before them keep theirs; the model records the overwrite.
TEST(ResolvedOptions, RepresentationSwitchesOnlyWhenNotTheDefault)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    const std::string paper = IntegratorTrainer(*p.model, *p.ae, o).resolved_options(p.samples.size());
    EXPECT_EQ(paper.find("balancing_velocity"), std::string::npos) << paper;
    EXPECT_EQ(paper.find("overwrite_dirichlet"), std::string::npos) << paper;
    EXPECT_EQ(paper.find("boundary_input"), std::string::npos) << paper;
    EXPECT_NE(paper.find(";decoder=compiled"), std::string::npos) << paper;
    EXPECT_EQ(paper.find("float32"), std::string::npos) << paper;
    o.balancing_velocity = BalancingVelocity::MeanSpeed;
    o.overwrite_dirichlet = true;
    o.boundary_input = BoundaryInputKind::Pose;
    o.float32_decoder = true;
    IntegratorTrainer changed(*p.model, *p.ae, o);
    const std::string text = changed.resolved_options(p.samples.size());
    EXPECT_NE(text.find(";balancing_velocity=mean_speed"), std::string::npos) << text;
    EXPECT_NE(text.find(";overwrite_dirichlet=on"), std::string::npos) << text;
    EXPECT_NE(text.find(";boundary_input=pose"), std::string::npos) << text;
    EXPECT_NE(text.find(";decoder=compiled_float32"), std::string::npos) << text;
    EXPECT_EQ(o.describe().find("self_supervised, hidden [256,256,256,256,256], noise on, balancing on (mean speed), "
                                "Dirichlet overwritten, boundary pose in p, float32 decoder, lr"),
              0u)
        << o.describe();

    const TrainingSamples samples = make_training_samples(*p.ae, p.data, changed.boundary_input());
    LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), samples.p.rows(), {8}, 3);
    changed.prepare(net, samples);
    EXPECT_TRUE(net.overwrite_dirichlet);
}

TEST(TrainingNoise, DoublesTheBatchWithBoundedLatentNoise)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    o.training_noise = true;
    IntegratorTrainer trainer(*p.model, *p.ae, o);
    Rng rng(5);
    const std::vector<Index> idx = all_indices(std::min<Index>(p.samples.size(), 10));
    const Index n = Index(idx.size());
    const IntegratorBatch b = trainer.make_batch(p.samples, idx, rng);
    ASSERT_EQ(b.size(), 2 * n);
    const Index L = p.ae->latent_dim();
    const MatrixXd clean = b.z_prev().leftCols(n);
    const VectorXd mean = clean.rowwise().mean();
    const VectorXd std = ((clean.colwise() - mean).array().square().rowwise().sum() / double(n)).sqrt();
    for (Index i = 0; i < n; ++i) {
        EXPECT_EQ(b.z_prev().col(i), p.samples.z_prev.col(idx[size_t(i)]));
        const VectorXd noise = b.z_prev().col(n + i) - b.z_prev().col(i);
        for (Index c = 0; c < L; ++c) EXPECT_LE(std::abs(noise[c]), 0.1 * std[c] + 1e-15);
        // Boundary parameters and targets unchanged; the noisy inputs carry the noisy latents.
        EXPECT_EQ(b.inputs().col(n + i).tail(b.inputs().rows() - 2 * L), b.inputs().col(i).tail(b.inputs().rows() - 2 * L));
        EXPECT_EQ(b.inputs().col(n + i).head(L), b.z_prev().col(n + i));
        EXPECT_EQ(b.targets().col(n + i), b.targets().col(i));
    }
    EXPECT_GT((b.z_prev().rightCols(n) - b.z_prev().leftCols(n)).norm(), 0.0);
    EXPECT_GT((b.z_prev2().rightCols(n) - b.z_prev2().leftCols(n)).norm(), 0.0);

    o.training_noise = false;
    IntegratorTrainer plain(*p.model, *p.ae, o);
    EXPECT_EQ(plain.make_batch(p.samples, idx, rng).size(), n);
}

TEST(TrainingNoise, SharedDrawPerturbsBothLatentsByTheSameUniformSample)
{
    // Issue 39: noise_draw = "shared" uses one U(-1, 1) draw per sample and component for
    // z_{t-1} and z_{t-2}, each scaled by its own latent's batch std; "independent" one each.
    TinyProblem p;
    const std::vector<Index> idx = all_indices(std::min<Index>(p.samples.size(), 12));
    const Index n = Index(idx.size());
    // The unit draws u = (z_noisy − z) / (0.1 std) of one input latent over the batch.
    auto unit_draws = [&](Eigen::Ref<const MatrixXd> z) {
        const MatrixXd clean = z.leftCols(n);
        const VectorXd mean = clean.rowwise().mean();
        const VectorXd std = ((clean.colwise() - mean).array().square().rowwise().sum() / double(n)).sqrt();
        return MatrixXd((z.rightCols(n) - clean).array().colwise() / (0.1 * std).array());
    };
    for (const NoiseDraw draw : {NoiseDraw::Shared, NoiseDraw::Independent}) {
        IntegratorTrainOptions o;
        o.training_noise = true;
        o.noise_draw = draw;
        IntegratorTrainer trainer(*p.model, *p.ae, o);
        Rng rng(9);
        const IntegratorBatch b = trainer.make_batch(p.samples, idx, rng);
        const MatrixXd u1 = unit_draws(b.z_prev()), u2 = unit_draws(b.z_prev2());
        EXPECT_LE(u1.cwiseAbs().maxCoeff(), 1.0 + 1e-9);
        EXPECT_LE(u2.cwiseAbs().maxCoeff(), 1.0 + 1e-9);
        EXPECT_GT(u1.cwiseAbs().maxCoeff(), 0.1);  // there is noise
        if (draw == NoiseDraw::Shared)
            EXPECT_LE((u1 - u2).cwiseAbs().maxCoeff(), 1e-9) << to_string(draw);
        else
            EXPECT_GT((u1 - u2).cwiseAbs().maxCoeff(), 0.1) << to_string(draw);
    }
    EXPECT_EQ(noise_draw_from_string("shared"), NoiseDraw::Shared);
    EXPECT_THROW(noise_draw_from_string("same"), ConfigError);
}

TEST(DataBalancing, DividesEachSampleByItsMeanVelocity)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    o.training_noise = false;
    o.hidden = {8};
    LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    prepare(net, p.samples);
    Rng rng(1);
    const double floor = 1e-4;
    for (Index i : {Index(0), Index(5), p.samples.size() - 1}) {
        const IntegratorBatch b = IntegratorTrainer(*p.model, *p.ae, o).make_batch(p.samples, {i}, rng);
        o.data_balancing = false;
        IntegratorTrainer off(*p.model, *p.ae, o);
        const double plain = off.loss(net, b);
        o.data_balancing = true;
        IntegratorTrainer on(*p.model, *p.ae, o);
        on.set_velocity_floor(floor);
        const double balanced = on.loss(net, b);
        // |v_{t−1}| of the decoded inputs, computed independently.
        const MatrixXd x1 = p.ae->decode(b.z_prev(), b.targets_prev());
        const MatrixXd x2 = p.ae->decode(b.z_prev2(), b.targets_prev2());
        Vector3d v = Vector3d::Zero();
        for (Index j = 0; j < p.model->num_vertices(); ++j) v += (x1.col(0) - x2.col(0)).segment<3>(3 * j);
        v /= double(p.model->num_vertices()) * p.model->dt();
        EXPECT_NEAR(balanced, plain / std::max(v.norm(), floor), 1e-9 * std::abs(plain / std::max(v.norm(), floor)));
    }
}

// Rotation about the centroid: the mean vertex velocity vanishes (eq. 6 read literally puts
// every such sample at the floor), the mean vertex speed does not. A translation has equal
// speeds everywhere, so both give the same weight.
TEST(DataBalancing, MeanSpeedWeighsRotationsThatTheMeanVelocityPutsAtTheFloor)
{
    TinyProblem p;
    const double dt = p.model->dt();
    const VectorXd rest = flatten(p.data.physics.mesh.rest_positions);
    const Vector3d centroid = as_rows(rest).colwise().mean().transpose();
    const double floor = 1e-3;
    MatrixXd rotated(rest.size(), 3), translated(rest.size(), 3), before(rest.size(), 3);
    for (Index i = 0; i < 3; ++i) {
        before.col(i) = rest;
        // 0.5, 1, 1.5 rad/s about three axes through the centroid.
        const Matrix3d R = Eigen::AngleAxisd(0.5 * double(i + 1) * dt, Vector3d::Unit(i)).toRotationMatrix();
        VectorXd x = rest;
        for (Index j = 0; j < rest.size() / 3; ++j) x.segment<3>(3 * j) = R * (rest.segment<3>(3 * j) - centroid) + centroid;
        rotated.col(i) = x;
        translated.col(i) = rest + (VectorXd::LinSpaced(3, 0.1, 0.3).replicate(rest.size() / 3, 1) * double(i + 1) * dt);
    }
    IntegratorTrainOptions o;
    o.balancing_velocity = BalancingVelocity::MeanVelocity;
    IntegratorTrainer velocity(*p.model, *p.ae, o);
    o.balancing_velocity = BalancingVelocity::MeanSpeed;
    IntegratorTrainer speed(*p.model, *p.ae, o);
    velocity.set_velocity_floor(floor);
    speed.set_velocity_floor(floor);

    const VectorXd at_floor = velocity.balancing_weights(rotated, before);
    const VectorXd by_speed = speed.balancing_weights(rotated, before);
    for (Index i = 0; i < 3; ++i) {
        EXPECT_LT(balancing_speeds(rotated.col(i), before.col(i), dt, BalancingVelocity::MeanVelocity)[0], 1e-12);
        EXPECT_EQ(at_floor[i], 1.0 / floor) << "rotation " << i;
        // Independently: the mean over vertices of |ω × r| = mean |x_{t−1} − x_{t−2}| / h.
        double mean_speed = 0.0;
        for (Index j = 0; j < rest.size() / 3; ++j)
            mean_speed += (rotated.col(i).segment<3>(3 * j) - rest.segment<3>(3 * j)).norm() / dt;
        mean_speed /= double(rest.size() / 3);
        ASSERT_GT(mean_speed, 10.0 * floor);
        EXPECT_NEAR(by_speed[i], 1.0 / mean_speed, 1e-12 / mean_speed) << "rotation " << i;
    }
    const VectorXd t_velocity = velocity.balancing_weights(translated, before);
    const VectorXd t_speed = speed.balancing_weights(translated, before);
    for (Index i = 0; i < 3; ++i) {
        const double expected = 1.0 / (VectorXd::LinSpaced(3, 0.1, 0.3).norm() * double(i + 1));
        EXPECT_NEAR(t_velocity[i], expected, 1e-12 * expected) << "translation " << i;
        EXPECT_NEAR(t_speed[i], expected, 1e-12 * expected) << "translation " << i;
    }
}

// boundary_input = "pose": p = [the scene's parameters, the pose of the frame's Dirichlet
// targets] for each of the three frames; everything else as with the velocities alone; the
// trainer records the input in the model and refuses samples made the other way.
TEST(PoseBoundaryInput, SamplesAppendThePoseOfEachFramesTargets)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    o.boundary_input = BoundaryInputKind::Pose;
    IntegratorTrainer trainer(*p.model, *p.ae, o);
    const BoundaryInput pose = trainer.boundary_input();
    const TrainingSamples s = make_training_samples(*p.ae, p.data, pose);
    const Index P = p.samples.p.rows();
    ASSERT_EQ(s.p.rows(), P + BoundaryInput::kPoseSize);
    EXPECT_EQ(s.boundary_input, BoundaryInputKind::Pose);
    EXPECT_EQ(s.p.topRows(P), p.samples.p);
    EXPECT_EQ(s.p_prev.topRows(P), p.samples.p_prev);
    EXPECT_EQ(s.p_prev2.topRows(P), p.samples.p_prev2);
    EXPECT_EQ(s.z_prev, p.samples.z_prev);
    EXPECT_EQ(s.targets, p.samples.targets);
    for (Index i = 0; i < s.size(); ++i) {
        EXPECT_EQ(s.p.col(i).tail(BoundaryInput::kPoseSize), pose.pose(s.targets.col(i)));
        EXPECT_EQ(s.p_prev.col(i).tail(BoundaryInput::kPoseSize), pose.pose(s.targets_prev.col(i)));
        EXPECT_EQ(s.p_prev2.col(i).tail(BoundaryInput::kPoseSize), pose.pose(s.targets_prev2.col(i)));
    }

    LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), s.p.rows(), {8}, 3);
    trainer.prepare(net, s);
    EXPECT_EQ(net.boundary.kind(), BoundaryInputKind::Pose);
    EXPECT_EQ(net.boundary.rest_targets(), pose.rest_targets());
    LatentMlpModel velocity_net = LatentMlpModel::create(p.ae->latent_dim(), P, {8}, 3);
    EXPECT_THROW(trainer.prepare(velocity_net, p.samples), Error);
}

TEST(SelfSupervisedLoss, DecreasesOnATinyScene)
{
    TinyProblem p;
    IntegratorTrainOptions o;
    o.hidden = {32, 32};
    o.epochs = 1;
    o.batch_size = 8;
    o.learning_rate = 1e-3;
    o.progress = false;
    LatentMlpModel net = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    IntegratorTrainer first(*p.model, *p.ae, o);
    const double loss_after_1 = first.train(net, p.samples).final_loss;
    o.epochs = 60;
    LatentMlpModel net2 = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    IntegratorTrainer longer(*p.model, *p.ae, o);
    const double loss_after_60 = longer.train(net2, p.samples).final_loss;
    EXPECT_LT(loss_after_60, loss_after_1) << "60 epochs: " << loss_after_60 << ", 1 epoch: " << loss_after_1;
}

} // namespace
} // namespace lb

namespace lb {
namespace {

MatrixXd flat_weights(LatentMlpModel& m)
{
    std::vector<double> w;
    for (auto& p : m.network.parameters()) w.insert(w.end(), p.value.data(), p.value.data() + p.value.size());
    return Eigen::Map<MatrixXd>(w.data(), Index(w.size()), 1);
}

// Training 2N epochs straight, and a run killed after N epochs (its checkpoint written)
// then resumed, give the same weights (network, optimiser state and batches restored).
TEST(IntegratorCheckpoint, ResumeReproducesUninterruptedTraining)
{
    testing::TinyProblem p;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/integrator_resume";
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    IntegratorTrainOptions o;
    o.hidden = {16};
    o.batch_size = 8;
    o.learning_rate = 1e-3;
    o.progress = false;
    o.epochs = 6;
    LatentMlpModel straight = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    const IntegratorTrainSummary s_straight = IntegratorTrainer(*p.model, *p.ae, o).train(straight, p.samples);

    o.checkpoint_path = dir + "/ckpt.h5";
    o.checkpoint_every = 3;
    IntegratorTrainOptions killed = o;
    killed.interrupt = [](int epochs_done) { return epochs_done == 3; };
    LatentMlpModel first = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    const IntegratorTrainSummary s_first = IntegratorTrainer(*p.model, *p.ae, killed).train(first, p.samples);
    EXPECT_TRUE(s_first.interrupted);
    EXPECT_EQ(s_first.epochs_run, 3);
    ASSERT_TRUE(std::filesystem::exists(o.checkpoint_path));
    LatentMlpModel resumed = LatentMlpModel::create(p.ae->latent_dim(), p.samples.p.rows(), o.hidden, 3);
    const IntegratorTrainSummary s = IntegratorTrainer(*p.model, *p.ae, o).train(resumed, p.samples);
    EXPECT_TRUE(s.resumed);
    EXPECT_EQ(s.epochs_run, 6);
    EXPECT_EQ(s.final_loss, s_straight.final_loss);
    EXPECT_EQ(flat_weights(resumed), flat_weights(straight));
}

} // namespace
} // namespace lb
