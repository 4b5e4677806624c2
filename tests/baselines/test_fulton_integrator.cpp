// fulton_cubature, part 2: the latent L-BFGS step. ∇Φ against finite differences with
// and without cubature, on a penalty scene (cantilever) and on rods (hard roots); the
// precomputed PCA-coordinate objective against LatentPotential's full decode; all
// elements at unit weight reproducing fulton_full step for step; a small-cantilever
// rollout against the ground truth.
#include <gtest/gtest.h>

#include "baselines/fulton_cubature/fulton_integrator.hpp"
#include "eval/rollout.hpp"
#include "fulton_fixture.hpp"
#include "support/finite_difference.hpp"

namespace lb {
namespace {

using testing::FultonProblem;

Cubature quick_cubature(FultonProblem& p, int train_frames)
{
    PcaSplitDecoder split(*p.ae, *p.model);
    CubatureOptions o;
    o.tolerance = 0.02;
    o.max_elements = 60;
    o.candidates = 200;
    return train_cubature(*p.model, split, p.reconstructions(2, train_frames), o);
}

void check_objective_gradient(const std::string& scene, bool cubature)
{
    FultonProblem p(scene, 30, 24, 100);
    std::optional<Cubature> c;
    if (cubature) c = quick_cubature(p, 24);
    FultonIntegrator integrator("f", p.ae, *p.model, c, {});
    const SequenceData& seq = p.data.sequences[0];
    integrator.reset(seq.positions.row(4).transpose(), boundary_state(seq, 4), seq.positions.row(5).transpose(),
                     boundary_state(seq, 5));
    const BoundaryState bc = boundary_state(seq, 6);
    VectorXd z = integrator.latent();
    for (Index i = 0; i < z.size(); ++i) z[i] += 0.05 * double(i + 1) * (i % 2 ? -1.0 : 1.0);
    VectorXd g;
    integrator.objective(z, bc, &g);
    ASSERT_TRUE(g.allFinite());
    testing::FdOptions fd;
    fd.step = 1e-6;
    fd.tol = 1e-5;
    fd.scale = 1e-4 * g.lpNorm<Eigen::Infinity>();
    EXPECT_TRUE(testing::check_gradient([&](const VectorXd& y) { return integrator.objective(y, bc, nullptr); },
                                        [&](const VectorXd& y) {
                                            VectorXd gy;
                                            integrator.objective(y, bc, &gy);
                                            return gy;
                                        },
                                        z, fd, scene + (cubature ? " cubature" : " full") + " ∇Φ"));
}

TEST(FultonIntegrator, GradientMatchesFiniteDifferencesPenaltyFull) { check_objective_gradient("cantilever", false); }
TEST(FultonIntegrator, GradientMatchesFiniteDifferencesPenaltyCubature) { check_objective_gradient("cantilever", true); }
TEST(FultonIntegrator, GradientMatchesFiniteDifferencesRodsFull) { check_objective_gradient("rods_translate", false); }
TEST(FultonIntegrator, GradientMatchesFiniteDifferencesRodsCubature) { check_objective_gradient("rods_translate", true); }

/// The PCA-coordinate inertia, gravity and penalty equal the incremental potential of the
/// fully decoded state (LatentPotential), including the boundary's acceleration.
void check_against_latent_potential(const std::string& scene)
{
    FultonProblem p(scene, 30, 24, 50);
    FultonIntegrator integrator("f", p.ae, *p.model, std::nullopt, {});
    const SequenceData& seq = p.data.sequences[0];
    integrator.reset(seq.positions.row(10).transpose(), boundary_state(seq, 10), seq.positions.row(11).transpose(),
                     boundary_state(seq, 11));
    const BoundaryState bc = boundary_state(seq, 12);
    for (double shift : {0.0, 0.1, -0.3}) {
        const VectorXd z = integrator.latent() + VectorXd::Constant(integrator.latent().size(), shift);
        const double ours = integrator.objective(z, bc, nullptr);
        const double reference = integrator.reference_objective(z, bc);
        EXPECT_NEAR(ours, reference, 1e-9 * std::max(1.0, std::abs(reference))) << scene << " shift " << shift;
    }
}

TEST(FultonIntegrator, ObjectiveEqualsLatentPotentialCloth) { check_against_latent_potential("cloth"); }
TEST(FultonIntegrator, ObjectiveEqualsLatentPotentialRods) { check_against_latent_potential("rods_translate"); }

/// Cubature of every element at unit weight is the exact energy: the same objective as
/// fulton_full (to round-off: the sums run in a different order) and the same steps (to the
/// solver tolerance, which is where the round-off differences leave L-BFGS).
TEST(FultonIntegrator, AllElementsCubatureReproducesFultonFull)
{
    FultonProblem p("cantilever", 60, 50, 200);
    FultonOptions o;
    o.gradient_tolerance = 1e-7;  // 10× the default, above the round-off floor (~3e-8 here)
    FultonIntegrator full("full", p.ae, *p.model, std::nullopt, o);
    FultonIntegrator all("all", p.ae, *p.model, Cubature::all_elements(*p.model), o);
    const SequenceData& seq = p.data.sequences[0];
    for (FultonIntegrator* f : {&full, &all})
        f->reset(seq.positions.row(0).transpose(), boundary_state(seq, 0), seq.positions.row(1).transpose(),
                 boundary_state(seq, 1));
    const BoundaryState bc = boundary_state(seq, 2);
    for (double shift : {0.0, 0.05, -0.2}) {
        const VectorXd z = full.latent() + VectorXd::Constant(full.latent().size(), shift);
        VectorXd g_full, g_all;
        const double f_full = full.objective(z, bc, &g_full);
        const double f_all = all.objective(z, bc, &g_all);
        EXPECT_NEAR(f_all, f_full, 1e-12 * std::abs(f_full)) << "shift " << shift;
        EXPECT_LT((g_all - g_full).norm(), 1e-10 * g_full.norm()) << "shift " << shift;
    }
    double worst = 0.0;
    for (Index t = 2; t < 60; ++t) {
        full.step(boundary_state(seq, t));
        all.step(boundary_state(seq, t));
        worst = std::max(worst, (full.positions() - all.positions()).lpNorm<Eigen::Infinity>());
    }
    EXPECT_LT(worst / p.model->length_scale(), 1e-7);
    EXPECT_EQ(full.unconverged_steps(), 0);
    EXPECT_EQ(all.unconverged_steps(), 0);
    EXPECT_NEAR(all.mean_iterations(), full.mean_iterations(), 0.2 * full.mean_iterations() + 0.5);
}

/// A rollout of the small cantilever (trained on 100 frames, rolled out to 300) stays
/// near the ground truth, with and without cubature, with the quickstart's autoencoder
/// (hidden 64-64, PCA 50, 800 epochs). Its error is dominated by the autoencoder, not the
/// step: the manifold reconstructs the early transient poorly (frame 2: 0.018 relative
/// RMSE, and a lower Φ than the encoded ground truth exists on it), so the latent step
/// lands near the static equilibrium at once and stays there; the steady state is then
/// within 0.001 of the ground truth.
TEST(FultonIntegrator, SmallCantileverRolloutFollowsGroundTruth)
{
    FultonProblem p("cantilever", 300, 100, 800, 64, 50);
    const SequenceData& seq = p.data.sequences[0];
    PcaSplitDecoder split(*p.ae, *p.model);
    CubatureOptions o;
    o.tolerance = 0.02;
    const Cubature c = train_cubature(*p.model, split, p.reconstructions(0, 100), o);
    FultonIntegrator full("full", p.ae, *p.model, std::nullopt, {});
    FultonIntegrator cub("cubature", p.ae, *p.model, c, {});
    const RolloutResult r_full = rollout(full, *p.model, seq);
    const RolloutResult r_cub = rollout(cub, *p.model, seq);
    const MatrixXd X = seq.positions.transpose();
    const double projection = p.ae->relative_rmse(X, seq.bc_positions.transpose());
    // Following the truth means staying within what the latent space can represent: the
    // rollout's error within twice the autoencoder's own projection error of the sequence
    // (its PCA layer is clamped to the training frames' rank, 10 here, so the projection is
    // about 0.002), and never above 1 % of the diagonal.
    ASSERT_LT(projection, 0.005);
    for (const RolloutResult* r : {&r_full, &r_cub}) {
        EXPECT_EQ(r->summary.stable_horizon, 300) << r->method;
        EXPECT_LT(r->summary.train.mean_rmse, 2.0 * projection) << r->method;
        EXPECT_LT(r->summary.test.mean_rmse, 2.0 * projection) << r->method;
        EXPECT_LT(r->summary.test.final_rmse, 2.0 * projection) << r->method;
    }
    std::printf("[ figures  ] small cantilever 300 frames: autoencoder projection RMSE %.5f, fulton_full test-window RMSE %.5f (%.2f "
                "it/step, %d unconverged, final %.5f), fulton_cubature test-window RMSE %.5f (%zu elements, %.2f it/step, %d unconverged)\n",
                projection, r_full.summary.test.mean_rmse, full.mean_iterations(), full.unconverged_steps(),
                r_full.summary.test.final_rmse, r_cub.summary.test.mean_rmse,
                c.elements.size(), cub.mean_iterations(), cub.unconverged_steps());
}

} // namespace
} // namespace lb
