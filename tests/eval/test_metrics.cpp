// The per-frame metrics and their summary (issue 10, "Honest evaluation"). Each test
// names the finding it covers and what the code before the issue produced on it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "eval/metrics.hpp"
#include "eval/summary_schema.hpp"
#include "mesh/generators.hpp"
#include "sim/physics_model.hpp"

namespace lb {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// A per-frame table of T frames with the given relative RMSE per frame and benign
/// values elsewhere (ground-truth kinetic energies 1 J, predicted ones `ke`).
MatrixXd metrics_table(const std::vector<double>& rmse, double ke = 1.0)
{
    const Index T = Index(rmse.size());
    MatrixXd m = MatrixXd::Zero(T, kNumMetricColumns);
    for (Index t = 0; t < T; ++t) {
        m(t, kRmse) = rmse[size_t(t)];
        m(t, kBcViolation) = 1e-3;
        m(t, kKinetic) = m(t, kKineticFree) = ke;
        m(t, kKineticGt) = m(t, kKineticFreeGt) = 1.0;
        m(t, kResidual) = 0.1;
        m(t, kStedSpatial) = 0.03;
        m(t, kStedTemporal) = 0.08;
        m(t, kIntegrateSeconds) = 1e-4;
        m(t, kDecodeSeconds) = 2e-4;
    }
    return m;
}

/// What rollout() leaves after a non-finite state at frame `stop`: the prediction's
/// columns NaN from there on (the ground truth's too, as before issue 10).
void diverge_from(MatrixXd& m, Index stop)
{
    m.bottomRows(m.rows() - stop).setConstant(kNan);
}

// ---- finding 1: a diverged rollout reads as diverged --------------------------------------

TEST(Summarize, NanRowsAfterTheStopNeverGiveAZeroOrAPerfectScore)
{
    // Before issue 10: ke_ratio was 0 (the NaN ground-truth KE after the stop failed
    // ke_gt > 0) and the NaN rows entered every mean.
    std::vector<double> rmse(40, 0.01);
    MatrixXd m = metrics_table(rmse);
    diverge_from(m, 25);
    const RolloutSummary s = summarize(m, 1.0, 20);
    EXPECT_EQ(s.stable_horizon, 25);
    EXPECT_EQ(s.horizon_loose, 25);
    EXPECT_EQ(s.horizon_tight, 25);
    // The training window (frames 2..19) is complete and fine.
    EXPECT_EQ(s.train.evaluated_frames, 18);
    EXPECT_DOUBLE_EQ(s.train.mean_rmse, 0.01);
    EXPECT_DOUBLE_EQ(s.train.ke_ratio, 1.0);
    // The test window (20..39) is aggregated up to the horizon only and says so.
    EXPECT_EQ(s.test.window_frames, 20);
    EXPECT_EQ(s.test.evaluated_frames, 5);
    EXPECT_DOUBLE_EQ(s.test.mean_rmse, 0.01);
    EXPECT_DOUBLE_EQ(s.test.ke_ratio, 1.0);
    EXPECT_DOUBLE_EQ(s.test.frac_blowup, 15.0 / 20.0);
    for (const TableCell& c : summary_table_cells(s, SummaryScope::Test)) EXPECT_NE(c.text, "0");
    // Timings of the stepped frames, not NaN.
    EXPECT_NEAR(s.total_ms, 0.3, 1e-12);

    // Diverged before the test window: every error of the test window is "diverged".
    MatrixXd early = metrics_table(rmse);
    diverge_from(early, 8);
    const RolloutSummary e = summarize(early, 1.0, 20);
    EXPECT_EQ(e.test.evaluated_frames, 0);
    EXPECT_TRUE(std::isnan(e.test.ke_ratio)) << "was 0 before issue 10";
    EXPECT_TRUE(std::isnan(e.test.max_bc_violation));
    const std::vector<std::string> columns = summary_table_columns();
    const std::vector<TableCell> cells = summary_table_cells(e, SummaryScope::Test);
    for (size_t c = 0; c < cells.size(); ++c) {
        EXPECT_NE(cells[c].text, "0") << columns[c];
        if (columns[c] == "mean RMSE" || columns[c] == "KE ratio (free)" || columns[c] == "max BC viol. (m)" ||
            columns[c] == "residual" || columns[c] == "STED (1-ring)") {
            EXPECT_EQ(cells[c].text, "diverged @8") << columns[c];
        }
    }
}

TEST(Summarize, KeRatioWithoutGroundTruthMotionIsUndefinedNotZero)
{
    MatrixXd m = metrics_table(std::vector<double>(12, 0.01), 0.5);
    m.col(kKineticFreeGt).setZero();
    const RolloutSummary s = summarize(m, 1.0, 6);
    EXPECT_TRUE(std::isnan(s.test.ke_ratio));
    const std::vector<std::string> columns = summary_table_columns();
    const auto ke = std::find(columns.begin(), columns.end(), "KE ratio (free)");
    ASSERT_NE(ke, columns.end());
    EXPECT_EQ(summary_table_cells(s, SummaryScope::Test)[size_t(ke - columns.begin())].text, "n/a");
}

// ---- finding 2: training and test windows apart ----------------------------------------------

TEST(Summarize, TrainingAndTestWindowsAreReportedApart)
{
    // Before issue 10 one mean covered frames 2..T−1: (18·0.01 + 20·0.04)/38 = 0.0258.
    std::vector<double> rmse(40, 0.01);
    for (size_t t = 20; t < rmse.size(); ++t) rmse[t] = 0.04;
    const RolloutSummary s = summarize(metrics_table(rmse), 2.0, 20);
    EXPECT_EQ(s.train.window_frames, 18);
    EXPECT_EQ(s.test.window_frames, 20);
    EXPECT_DOUBLE_EQ(s.train.mean_rmse, 0.01);
    EXPECT_DOUBLE_EQ(s.test.mean_rmse, 0.04);
    EXPECT_DOUBLE_EQ(s.test.final_rmse, 0.04);
    EXPECT_DOUBLE_EQ(s.test.m_rms, 0.08);  // metres: 0.04 × L = 2
    EXPECT_EQ(window_label(s, SummaryScope::Train), "train (frames 2-19)");
    EXPECT_EQ(window_label(s, SummaryScope::Test), "test (frames >= 20)");
    // A sequence that is all test (train_frames = 0): an empty training window.
    const RolloutSummary all_test = summarize(metrics_table(rmse), 1.0, 0);
    EXPECT_EQ(all_test.train.window_frames, 0);
    EXPECT_EQ(all_test.test.window_frames, 38);
    EXPECT_EQ(summary_table_cells(all_test, SummaryScope::Train).back().text, "0.3");  // the time
}

TEST(Summarize, ErrorsAreAggregatedBeforeTheStableHorizonOnly)
{
    // A finite blow-up (RMSE 3 from frame 30): its frames do not enter the test errors.
    std::vector<double> rmse(40, 0.01);
    for (size_t t = 30; t < rmse.size(); ++t) rmse[t] = 3.0;
    const RolloutSummary s = summarize(metrics_table(rmse), 1.0, 20);
    EXPECT_EQ(s.stable_horizon, 30);
    EXPECT_EQ(s.test.evaluated_frames, 10);
    EXPECT_DOUBLE_EQ(s.test.mean_rmse, 0.01);
    EXPECT_DOUBLE_EQ(s.test.frac_blowup, 0.5);
}

// ---- finding 3: tiered horizons -----------------------------------------------------------

TEST(Summarize, HorizonsInTiersAndABoundaryTransientIsNotADivergence)
{
    // Before issue 10, a boundary violation > 0.1 L at one frame ended the stable horizon
    // (the supervised cantilever "diverged" at frame 6 and then tracked the truth).
    std::vector<double> rmse(100, 0.005);
    for (size_t t = 30; t < 100; ++t) rmse[t] = 0.05;
    for (size_t t = 60; t < 100; ++t) rmse[t] = 0.2;
    for (size_t t = 90; t < 100; ++t) rmse[t] = 0.7;
    MatrixXd m = metrics_table(rmse);
    m(6, kBcViolation) = 0.3;  // a transient of 0.3 L
    const RolloutSummary s = summarize(m, 1.0, 50);
    EXPECT_EQ(s.stable_horizon, 90);
    EXPECT_EQ(s.horizon_loose, 60);
    EXPECT_EQ(s.horizon_tight, 30);
    EXPECT_DOUBLE_EQ(s.train.max_bc_violation, 0.3);  // still reported
    EXPECT_DOUBLE_EQ(s.train.frac_tight, 20.0 / 48.0);
    EXPECT_DOUBLE_EQ(s.train.frac_loose, 0.0);
    EXPECT_DOUBLE_EQ(s.test.frac_loose, 40.0 / 50.0);
    EXPECT_DOUBLE_EQ(s.test.frac_blowup, 10.0 / 50.0);
    EXPECT_DOUBLE_EQ(s.test.frac_tight, 1.0);
    // A stable run: every horizon is the frame count.
    const RolloutSummary ok = summarize(metrics_table(std::vector<double>(30, 0.001)), 1.0, 10);
    EXPECT_EQ(ok.stable_horizon, 30);
    EXPECT_EQ(ok.horizon_loose, 30);
    EXPECT_EQ(ok.horizon_tight, 30);
    EXPECT_DOUBLE_EQ(ok.test.frac_tight, 0.0);
}

// ---- models for the per-frame metrics ---------------------------------------------------

PhysicsModel cloth_model(int n, bool pinned = true)
{
    ClothGridOptions o;
    o.nx = o.ny = n;
    PhysicsSpec spec;
    spec.mesh = make_cloth_grid(o);
    spec.material.youngs_modulus = 1e5;
    spec.material.thickness = 1e-3;
    spec.material.density = 200.0;
    if (pinned) spec.bc_indices = {0, n - 1};
    return PhysicsModel(spec);
}

PhysicsModel beam_model()
{
    TetBeamOptions o;
    o.nx = 4;
    o.ny = o.nz = 1;
    PhysicsSpec spec;
    spec.mesh = make_tet_beam(o);
    spec.material.youngs_modulus = 1e6;
    for (Index i = 0; i < spec.mesh.num_vertices(); ++i) {
        if (spec.mesh.rest_positions(i, 0) < 1e-9) spec.bc_indices.push_back(int(i));
    }
    return PhysicsModel(spec);
}

Matrix3d rotation_about(const Vector3d& axis, double angle) { return Eigen::AngleAxisd(angle, axis.normalized()).matrix(); }

/// x with every vertex moved by p ↦ R p + t.
VectorXd moved(const VectorXd& x, const Matrix3d& R, const Vector3d& t)
{
    VectorXd y(x.size());
    for (Index i = 0; i < x.size() / 3; ++i) y.segment<3>(3 * i) = R * x.segment<3>(3 * i) + t;
    return y;
}

// ---- finding 4: kinetic energy of the free DOFs relative to the boundary's rigid motion -----

TEST(RigidMotion, KabschRecoversARotationAndFallsBackToATranslation)
{
    MatrixX3d from(4, 3);
    from << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
    const Matrix3d R = rotation_about({1, 2, 3}, 0.4);
    const Vector3d t(0.3, -0.2, 0.5);
    const MatrixX3d to = ((from * R.transpose()).rowwise() + t.transpose());
    const RigidMotion m = fit_rigid_motion(from, to);
    EXPECT_LT((m.rotation - R).norm(), 1e-12);
    EXPECT_LT((m.apply(Vector3d(0.7, 0.1, -2.0)) - (R * Vector3d(0.7, 0.1, -2.0) + t)).norm(), 1e-12);
    // Two points: the rotation about their line is undetermined: translation only.
    const RigidMotion two = fit_rigid_motion(from.topRows(2), to.topRows(2));
    EXPECT_EQ(two.rotation, Matrix3d::Identity());
    EXPECT_LT((two.to_centroid - two.from_centroid - (to.topRows(2).colwise().mean() - from.topRows(2).colwise().mean()).transpose()).norm(), 1e-12);
    const RigidMotion none = fit_rigid_motion(MatrixX3d(0, 3), MatrixX3d(0, 3));
    EXPECT_EQ(none.apply(Vector3d(1, 2, 3)), Vector3d(1, 2, 3));
}

TEST(RigidMotion, RestFrameAgreesWithTheGeneralFit)
{
    // RestFrame (the encoding's rigid frame and the boundary pose) fits the same motion as
    // fit_rigid_motion from its rest points, without allocating per call.
    MatrixX3d from(4, 3);
    from << 0.0, 0.0, 0.0, 1.0, 0.2, 0.0, 0.1, 1.3, 0.4, 0.5, 0.5, 1.1;
    const Matrix3d R = rotation_about({-1, 2, 0.5}, 1.1);
    const Vector3d t(-0.4, 0.25, 2.0);
    const MatrixX3d to = ((from * R.transpose()).rowwise() + t.transpose());
    const VectorXd rest = Eigen::Map<const VectorXd>(MatrixXd(from.transpose()).data(), from.size());
    const VectorXd now = Eigen::Map<const VectorXd>(MatrixXd(to.transpose()).data(), to.size());
    const RestFrame frame(rest);
    EXPECT_EQ(frame.size(), 4);
    EXPECT_TRUE(frame.fixes_rotation());
    const RigidMotion m = fit_rigid_motion(from, to);
    EXPECT_LT((frame.rotation(now.data()) - R).norm(), 1e-12);
    EXPECT_LT((frame.rotation(now.data()) - m.rotation).norm(), 1e-12);
    EXPECT_LT((frame.centroid(now.data()) - m.to_centroid).norm(), 1e-12);
    // Collinear or too few points fix no rotation: the identity, as the general fit gives.
    const RestFrame line(rest.head(6));
    EXPECT_FALSE(line.fixes_rotation());
    EXPECT_EQ(line.rotation(now.data()), Matrix3d::Identity());
    VectorXd collinear(9);
    collinear << 0, 0, 0, 1, 1, 1, 2, 2, 2;
    EXPECT_FALSE(RestFrame(collinear).fixes_rotation());
}

TEST(MetricContext, RigidlyCarriedFreeDofsHaveNoRelativeKineticEnergy)
{
    // Before issue 10 only the lab-frame KE existed: the prescribed motion of the
    // Dirichlet set (the bunny's head) and everything it carries dominated it.
    const PhysicsModel model = beam_model();
    MetricContext context(model);
    const VectorXd x_prev = model.rest_state();
    const VectorXd x = moved(x_prev, rotation_about({0, 0, 1}, 0.05), Vector3d(0.02, 0.01, 0.0));
    EXPECT_GT(model.kinetic_energy(x, x_prev), 1e-4);
    EXPECT_LT(context.free_kinetic_energy(x, x_prev, x, x_prev), 1e-20);
    // A free vertex moving on its own: exactly its ½ m v².
    VectorXd y = x;
    Index free_vertex = 0;
    while (std::find(model.bc_indices().begin(), model.bc_indices().end(), int(free_vertex)) != model.bc_indices().end())
        ++free_vertex;
    y[3 * free_vertex + 2] += 0.003;
    const double v = 0.003 / model.dt();
    EXPECT_NEAR(context.free_kinetic_energy(y, x_prev, x, x_prev), 0.5 * model.masses()[free_vertex] * v * v, 1e-12);
    // Fixed boundary: the free DOFs' ordinary KE.
    const VectorXd z = x_prev + VectorXd::Constant(x_prev.size(), 1e-3);
    double expected = 0.0;
    const VectorXi map = model.dof_to_unknown();
    for (Index d = 0; d < z.size(); ++d) {
        if (map[d] >= 0) expected += 0.5 * model.masses()[d / 3] * std::pow(1e-3 / model.dt(), 2);
    }
    EXPECT_NEAR(context.free_kinetic_energy(z, x_prev, x_prev, x_prev), expected, 1e-12 * expected);
}

TEST(Summarize, KeRatioUsesTheFreeDofColumns)
{
    MatrixXd m = metrics_table(std::vector<double>(12, 0.01));
    m.col(kKinetic).setConstant(100.0);  // lab frame, dominated by prescribed motion
    m.col(kKineticGt).setConstant(100.0);
    m.col(kKineticFree).setConstant(0.5);
    m.col(kKineticFreeGt).setConstant(1.0);
    EXPECT_DOUBLE_EQ(summarize(m, 1.0, 6).test.ke_ratio, 0.5);
}

// ---- finding 5: STED with local neighbourhoods ----------------------------------------------

TEST(MetricContext, StedSpatialMeasuresLocalDeviationsNotAUniformScale)
{
    // Before issue 10 the spatial term was the global RMS of relative edge differences:
    // 0.1 for a uniform 10 % scale, which Vasa & Skala's local deviation leaves at 0.
    const PhysicsModel model = cloth_model(6, false);
    MetricContext context(model);
    const VectorXd gt = model.rest_state();
    const VectorXd scaled = 1.1 * gt;
    EXPECT_NEAR(context.sted_terms(scaled, scaled, gt, gt).first, 0.0, 1e-12);
    // One vertex displaced: its neighbourhoods deviate.
    VectorXd bumped = gt;
    bumped[3 * 14 + 2] += 0.05;
    EXPECT_GT(context.sted_terms(bumped, bumped, gt, gt).first, 1e-3);
    // Temporal term: the same shapes, one vertex moving faster than the truth by one
    // local edge length per frame.
    const VectorXd gt_prev = gt;
    VectorXd x = gt, x_prev = gt;
    x_prev[3 * 14 + 2] -= 0.2;  // the prediction's vertex 14 moved 0.2 m; the truth did not
    const auto [spatial, temporal] = context.sted_terms(x, x_prev, gt, gt_prev);
    EXPECT_NEAR(spatial, 0.0, 1e-12);
    EXPECT_GT(temporal, 0.0);
    EXPECT_LT(temporal, 0.2);  // one vertex of 36, a few edge lengths
}

TEST(Summarize, StedCombinesTheTermsAsAHypotenuse)
{
    const RolloutSummary s = summarize(metrics_table(std::vector<double>(12, 0.01)), 1.0, 6);
    EXPECT_DOUBLE_EQ(s.test.sted, std::hypot(0.03, kStedTemporalWeight * 0.08));  // was 0.03 + 0.5 · 0.08
}

// ---- finding 6: the physics residual per DOF --------------------------------------------------

TEST(MetricContext, ResidualIsPerDofAndComparableAcrossResolutions)
{
    // At rest with zero velocity the free-DOF gradient is the weight m_i g on the z DOFs:
    // per-DOF RMS ≈ m̄|g|/√3 at any resolution. Before issue 10 the 2-norm over the free
    // DOFs over m̄(|g| + L/h²) grew with √N (ratio ≈ 2 between these two grids).
    double residual[2];
    int k = 0;
    for (int n : {5, 10}) {
        const PhysicsModel model = cloth_model(n);
        MetricContext context(model);
        EXPECT_DOUBLE_EQ(context.residual_scale(), model.masses().mean() * 9.81);
        const VectorXd x = model.rest_state();
        VectorXd bc(3 * model.bc_indices().size());
        for (size_t b = 0; b < model.bc_indices().size(); ++b) bc.segment<3>(3 * Index(b)) = x.segment<3>(3 * model.bc_indices()[b]);
        Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(kNumMetricColumns);
        context.frame_metrics(x, x, x, x, x, bc, row);
        residual[k++] = row[kResidual];
        EXPECT_NEAR(row[kRmse], 0.0, 1e-15);
    }
    EXPECT_NEAR(residual[0], 1.0 / std::sqrt(3.0), 0.15);
    EXPECT_NEAR(residual[1], 1.0 / std::sqrt(3.0), 0.15);
    EXPECT_NEAR(residual[1] / residual[0], 1.0, 0.15);
}

} // namespace
} // namespace lb
