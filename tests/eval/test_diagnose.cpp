// The error decomposition (eval/diagnose.hpp) on a short small cantilever: the truth
// row is exact, the full-space simulator's one step from the truth reproduces the truth,
// a projection through an untrained autoencoder is not exact, and a step that returns
// NaN reads as diverged.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "eval/diagnose.hpp"
#include "integrators/full_space_integrator.hpp"
#include "latent/autoencoder.hpp"
#include "support/small_scene.hpp"

namespace lb {
namespace {

class NanIntegrator final : public Integrator {
public:
    explicit NanIntegrator(Index dofs) : m_x(VectorXd::Constant(dofs, std::numeric_limits<double>::quiet_NaN())) { }
    std::string name() const override { return "nan"; }
    void reset(const VectorXd&, const BoundaryState&, const VectorXd&, const BoundaryState&) override { }
    StepTiming step(const BoundaryState&) override { return {}; }
    const VectorXd& positions() const override { return m_x; }
    const VectorXd& latent() const override { return m_z; }

private:
    VectorXd m_x, m_z;
};

TEST(Diagnose, DecomposesOnTheSmallCantilever)
{
    const Dataset data = lb::testing::simulate_small_scene("cantilever", 20, 12);
    const PhysicsModel model(data.physics);
    AutoencoderOptions ao;
    ao.latent_dim = 3;
    ao.hidden = {16, 16};
    ao.pca_dim = 6;
    Autoencoder ae(data.physics, ao, 0);
    ae.initialize_pca(ae.encoding().to_features(training_frames(data).positions));

    Diagnosis d(model, data, {});
    d.add_autoencoder(ae);
    const Scene scene = load_scene_from_string(data.scene_toml, "dataset scene", ".");
    FullSpaceIntegrator full(model, scene.newton);
    d.add_one_step(full, "(d) one step");
    NanIntegrator nan(model.num_dofs());
    d.add_one_step(nan, "(d) one step");

    const auto& rows = d.rows();
    ASSERT_EQ(rows.size(), 4u);
    const DiagnosisRow& truth = rows[0];
    EXPECT_EQ(truth.train.frames, 10);  // t = 2 … 11
    EXPECT_EQ(truth.test.frames, 8);    // t = 12 … 19
    EXPECT_EQ(truth.train.rmse, 0.0);
    EXPECT_EQ(truth.test.rmse, 0.0);
    EXPECT_DOUBLE_EQ(truth.test.elastic_ratio, 1.0);
    EXPECT_LT(truth.train.residual, 1e-3);  // the simulator converged: a small fraction of a vertex weight

    const DiagnosisRow& projection = rows[1];
    EXPECT_GT(projection.train.rmse, 1e-6);  // an untrained network does not reproduce the frames
    EXPECT_TRUE(std::isfinite(projection.test.rmse));
    EXPECT_GT(projection.train.residual, truth.train.residual);

    const DiagnosisRow& step = rows[2];
    EXPECT_EQ(step.method, full.name());
    EXPECT_LT(step.train.rmse, 1e-6);
    EXPECT_LT(step.test.rmse, 1e-6);

    const DiagnosisRow& diverged = rows[3];
    EXPECT_TRUE(std::isinf(diverged.train.rmse));
    EXPECT_TRUE(std::isinf(diverged.test.rmse));
    const std::string md = to_markdown(d.table("cantilever"));
    EXPECT_NE(md.find("diverged"), std::string::npos) << md;

    // (e): a rollout that blew up at frame 9, before its test window, reads as diverged
    // there in every column (never as 0), and its worst horizon is shown.
    RolloutRecord blown;
    blown.method = "blown";
    blown.sequence = data.sequences[0].name;
    blown.summary.stable_horizon = 9;
    blown.summary.train.window_frames = 10;
    blown.summary.train.mean_rmse = 0.25;
    blown.summary.train.mean_residual = 3.0;
    blown.summary.train.max_bc_violation = 0.01;
    blown.summary.test.window_frames = 8;
    blown.summary.test.mean_rmse = std::numeric_limits<double>::quiet_NaN();
    blown.summary.test.mean_residual = std::numeric_limits<double>::quiet_NaN();
    blown.summary.test.max_bc_violation = 0.0;
    d.add_rollout({blown});
    ASSERT_EQ(d.rows().size(), 5u);
    const DiagnosisRow& e = d.rows()[4];
    EXPECT_EQ(e.stable_horizon, 9);
    EXPECT_DOUBLE_EQ(e.train.rmse, 0.25);
    EXPECT_TRUE(std::isinf(e.test.rmse));
    EXPECT_TRUE(std::isinf(e.test.residual));
    EXPECT_TRUE(std::isinf(e.test.bc_violation));
    RolloutRecord other = blown;
    other.sequence = "not in this dataset";
    d.add_rollout({other});
    EXPECT_EQ(d.rows().size(), 5u);  // sequences outside the diagnosis are ignored

    DiagnoseOptions strided;
    strided.stride = 5;
    Diagnosis every_fifth(model, data, strided);
    every_fifth.add_autoencoder(ae);
    EXPECT_EQ(every_fifth.rows()[0].train.frames + every_fifth.rows()[0].test.frames, 4);  // t = 2, 7, 12, 17
    strided.stride = 0;
    EXPECT_THROW(Diagnosis(model, data, strided), ConfigError);
}

} // namespace
} // namespace lb
