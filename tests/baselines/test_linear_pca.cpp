#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>

#include "baselines/linear_pca/linear_pca.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "eval/rollout.hpp"
#include "io/hdf5.hpp"
#include "scene/scene.hpp"
#include "support/finite_difference.hpp"
#include "support/small_scene.hpp"

namespace lb {
namespace {

struct SmallData {
    Dataset data;
    std::unique_ptr<PhysicsModel> model;

    SmallData(const std::string& scene, int frames)
    {
        data = testing::simulate_small_scene(scene, frames, frames);
        model = std::make_unique<PhysicsModel>(data.physics);
    }
};

/// The reduced objective E(Jq + c) and its gradient Jᵀ∇E agree with finite
/// differences, with the Dirichlet penalty (cantilever) and with hard rod roots.
void check_reduced_gradient(const std::string& scene)
{
    SmallData d(scene, 20);
    LinearPcaIntegrator integrator("pca", *d.model, LinearPcaSubspace::fit(d.data, 5), {});
    const SequenceData& seq = d.data.sequences[0];
    integrator.reset(seq.positions.row(4).transpose(), boundary_state(seq, 4), seq.positions.row(5).transpose(),
                     boundary_state(seq, 5));
    const BoundaryState bc = boundary_state(seq, 6);
    const VectorXd q = integrator.latent() + VectorXd::Constant(integrator.dim(), 1e-3);
    testing::FdOptions fd;
    fd.step = 1e-6;
    fd.tol = 1e-5;
    fd.scale = 1e-6;
    EXPECT_TRUE(testing::check_gradient([&](const VectorXd& y) { return integrator.reduced_value(y, bc, nullptr); },
                                        [&](const VectorXd& y) {
                                            VectorXd g;
                                            integrator.reduced_value(y, bc, &g);
                                            return g;
                                        },
                                        q, fd, scene + " reduced gradient"));
}

TEST(LinearPca, ReducedGradientMatchesFiniteDifferencesWithPenalty) { check_reduced_gradient("cantilever"); }
TEST(LinearPca, ReducedGradientMatchesFiniteDifferencesWithRodRoots) { check_reduced_gradient("rods_translate"); }

// A subspace that spans every frame of the sequence contains the full-space
// trajectory, so the reduced Newton solve must follow it (up to the penalty's
// give on the clamped vertices); a 1-dimensional subspace cannot.
TEST(LinearPca, FullRankSubspaceReproducesTheTrajectory)
{
    SmallData d("cantilever", 30);
    const SequenceData& seq = d.data.sequences[0];
    LinearPcaIntegrator full("pca_full", *d.model, LinearPcaSubspace::fit(d.data, 29), {});
    LinearPcaIntegrator one("pca_1", *d.model, LinearPcaSubspace::fit(d.data, 1), {});
    const RolloutResult r_full = rollout(full, *d.model, seq);
    const RolloutResult r_one = rollout(one, *d.model, seq);
    EXPECT_EQ(full.unconverged_steps(), 0);
    EXPECT_EQ(r_full.summary.stable_horizon, 30);
    EXPECT_LT(r_full.summary.train.mean_rmse, 1e-4) << "full-rank subspace left the trajectory";
    EXPECT_GT(r_one.summary.train.mean_rmse, 10.0 * r_full.summary.train.mean_rmse);
}

TEST(LinearPca, SaveLoadRoundTripAndShapeErrors)
{
    SmallData d("cantilever", 12);
    const LinearPcaSubspace s = LinearPcaSubspace::fit(d.data, 3);
    EXPECT_EQ(s.pca.dim(), 3);
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/linear_pca";
    std::filesystem::create_directories(dir);
    {
        h5::File f = h5::File::create(dir + "/pca.h5");
        s.save(f);
    }
    const h5::File f = h5::File::open(dir + "/pca.h5");
    const LinearPcaSubspace back = LinearPcaSubspace::load(f, d.data.physics);
    EXPECT_EQ(back.pca.basis, s.pca.basis);
    EXPECT_EQ(back.pca.mean, s.pca.mean);

    SmallData rods("rods_translate", 4);  // different feature count
    EXPECT_THROW(LinearPcaSubspace::load(f, rods.data.physics), IoError);
    {
        h5::File other = h5::File::create(dir + "/other.h5");
        other.write("x", VectorXd(VectorXd::Zero(3)));
    }
    EXPECT_THROW(LinearPcaSubspace::load(h5::File::open(dir + "/other.h5"), d.data.physics), IoError);
    EXPECT_THROW(LinearPcaSubspace::fit(d.data, 0), ConfigError);
}

} // namespace
} // namespace lb
