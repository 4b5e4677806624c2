#include "eval/diagnose.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "eval/metrics.hpp"
#include "latent/autoencoder.hpp"
#include "sim/physics_model.hpp"

namespace lb {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Sums over the frames of a window; finish() turns them into means.
struct WindowSums {
    int frames = 0;
    double rmse = 0.0, elastic = 0.0, elastic_gt = 0.0, residual = 0.0, bc = 0.0;

    void add(const Eigen::RowVectorXd& row)
    {
        ++frames;
        rmse += row[kRmse];
        elastic += row[kElastic];
        elastic_gt += row[kElasticGt];
        residual += row[kResidual];
        const double v = row[kBcViolation];
        bc = std::isnan(v) || std::isnan(bc) ? kNaN : std::max(bc, v);
    }
    DiagnosisWindow finish() const
    {
        DiagnosisWindow w;
        w.frames = frames;
        if (frames == 0) {
            w.rmse = w.elastic_ratio = w.residual = w.bc_violation = kNaN;
            return w;
        }
        w.rmse = rmse / frames;
        w.elastic_ratio = elastic_gt > 0.0 ? elastic / elastic_gt : kNaN;
        w.residual = residual / frames;
        w.bc_violation = bc;
        return w;
    }
};

VectorXd frame(const SequenceData& s, Index t) { return s.positions.row(t).transpose(); }

TableCell number(double v)
{
    if (std::isnan(v)) return TableCell::missing("—");
    if (std::isinf(v)) return TableCell("diverged", v);
    return TableCell::significant(v, 3);
}

} // namespace

bool gives_manifold_optimal_step(const std::string& method_name) { return method_name == "fulton_full"; }

std::string one_step_stage(const std::string& method_name)
{
    return gives_manifold_optimal_step(method_name) ? "(c) manifold-optimal step" : "(d) one step";
}

Diagnosis::Diagnosis(const PhysicsModel& model, const Dataset& data, DiagnoseOptions options)
    : m_model(model), m_data(data), m_options(std::move(options))
{
    if (m_options.stride < 1) throw ConfigError("diagnose: stride must be ≥ 1");
    if (m_options.sequences.empty()) {
        for (size_t s = 0; s < data.sequences.size(); ++s) m_options.sequences.push_back(s);
    }
    for (size_t s : m_options.sequences) {
        if (s >= data.sequences.size()) throw ConfigError("diagnose: sequence index out of range");
        for (Index t = 2; t < data.sequences[s].num_frames(); t += m_options.stride) m_frames.push_back({s, t});
    }
    if (m_frames.empty()) throw ConfigError("diagnose: the chosen sequences have no frame t ≥ 2");
}

void Diagnosis::add_autoencoder(Autoencoder& autoencoder)
{
    MetricContext context(m_model);
    const Index n_dofs = m_model.num_dofs();
    MatrixXd X(n_dofs, Index(m_frames.size())), targets;
    targets.resize(m_data.sequences.front().bc_positions.cols(), Index(m_frames.size()));
    for (size_t k = 0; k < m_frames.size(); ++k) {
        const SequenceData& s = m_data.sequences[m_frames[k].sequence];
        X.col(Index(k)) = frame(s, m_frames[k].t);
        targets.col(Index(k)) = s.bc_positions.row(m_frames[k].t).transpose();
    }
    const MatrixXd X_hat = autoencoder.decode(autoencoder.encode(X), targets);

    WindowSums truth[2], projection[2];
    Eigen::RowVectorXd row(kNumMetricColumns);
    for (size_t k = 0; k < m_frames.size(); ++k) {
        const SequenceData& s = m_data.sequences[m_frames[k].sequence];
        const Index t = m_frames[k].t;
        const int w = t < s.train_frames ? 0 : 1;
        const VectorXd gt = X.col(Index(k)), gt_prev = frame(s, t - 1), gt_prev2 = frame(s, t - 2);
        const VectorXd bc = targets.col(Index(k));
        row.setConstant(kNaN);
        context.frame_metrics(gt, gt_prev, gt_prev2, gt, gt_prev, bc, row);
        truth[w].add(row);
        row.setConstant(kNaN);
        context.frame_metrics(X_hat.col(Index(k)), gt_prev, gt_prev2, gt, gt_prev, bc, row);
        projection[w].add(row);
    }
    m_rows.push_back({"ground truth", "", truth[0].finish(), truth[1].finish()});
    m_rows.push_back({"(a, b) projection D(E(x))", "", projection[0].finish(), projection[1].finish()});
}

void Diagnosis::add_one_step(Integrator& integrator, const std::string& stage)
{
    MetricContext context(m_model);
    WindowSums sums[2];
    Eigen::RowVectorXd row(kNumMetricColumns);
    for (const FrameRef& f : m_frames) {
        const SequenceData& s = m_data.sequences[f.sequence];
        const Index t = f.t;
        const VectorXd gt = frame(s, t), gt_prev = frame(s, t - 1), gt_prev2 = frame(s, t - 2);
        const BoundaryState bc = boundary_state(s, t);
        VectorXd x = VectorXd::Constant(gt.size(), kNaN);
        try {
            integrator.reset(gt_prev2, boundary_state(s, t - 2), gt_prev, boundary_state(s, t - 1));
            integrator.step(bc);
            x = integrator.positions();
        } catch (const NumericalError&) {
            // counted as a diverged step below
        }
        row.setConstant(kNaN);
        context.frame_metrics(x, gt_prev, gt_prev2, gt, gt_prev, bc.targets, row);
        if (!x.allFinite()) row[kRmse] = std::numeric_limits<double>::infinity();
        sums[t < s.train_frames ? 0 : 1].add(row);
    }
    m_rows.push_back({stage, integrator.name(), sums[0].finish(), sums[1].finish()});
}

void Diagnosis::add_rollout(const std::vector<RolloutRecord>& records)
{
    if (records.empty()) return;
    DiagnosisRow r{"(e) rollout", records.front().method, {}, {}};
    struct Acc {
        int n = 0, frames = 0;
        double rmse = 0.0, residual = 0.0, bc = 0.0;
        bool diverged = false;
    } acc[2];
    int horizon = std::numeric_limits<int>::max();
    bool any = false;
    for (const RolloutRecord& rec : records) {
        bool covered = false;
        for (size_t s : m_options.sequences) covered |= m_data.sequences[s].name == rec.sequence;
        if (!covered) continue;
        any = true;
        horizon = std::min(horizon, rec.summary.stable_horizon);
        const SummaryWindow* windows[2] = {&rec.summary.train, &rec.summary.test};
        for (int w = 0; w < 2; ++w) {
            const SummaryWindow& win = *windows[w];
            acc[w].frames += win.window_frames;
            if (win.window_frames == 0) continue;
            ++acc[w].n;
            if (!std::isfinite(win.mean_rmse)) {
                // blew up before the window: every column of it reads as diverged
                acc[w].diverged = true;
                continue;
            }
            acc[w].rmse += win.mean_rmse;
            acc[w].residual += win.mean_residual;
            acc[w].bc = std::max(acc[w].bc, win.max_bc_violation);
        }
    }
    if (!any) return;
    DiagnosisWindow* out[2] = {&r.train, &r.test};
    for (int w = 0; w < 2; ++w) {
        out[w]->frames = acc[w].frames;
        out[w]->elastic_ratio = kNaN;
        const double inf = std::numeric_limits<double>::infinity();
        out[w]->rmse = acc[w].diverged ? inf : acc[w].n ? acc[w].rmse / acc[w].n : kNaN;
        out[w]->residual = acc[w].diverged ? inf : acc[w].n ? acc[w].residual / acc[w].n : kNaN;
        out[w]->bc_violation = acc[w].diverged ? inf : acc[w].n ? acc[w].bc : kNaN;
    }
    r.stable_horizon = horizon;
    m_rows.push_back(r);
}

Table Diagnosis::table(const std::string& scene_name) const
{
    Table table;
    table.title = "Error decomposition: " + scene_name;
    table.caption =
        "Where the error comes from (latentbench diagnose; eval/diagnose.hpp). Frames t ≥ 2 of the chosen "
        "sequences, every " + std::to_string(m_options.stride) +
        "-th; training window t < train_frames, test window the rest. RMSE relative to the rest bounding-box "
        "diagonal; E_el ratio = mean elastic energy of the row's states over the truth's; residual = per-DOF RMS "
        "of the full-space step gradient (true history) over m̄|g|; BC = max Dirichlet violation (m). "
        "(a, b): the autoencoder's projection of the truth; (c): fulton_full's one step from the encoded truth "
        "(the best step in this latent space); (d): the integrator's one step from the truth; (e): the whole "
        "rollout (mean RMSE before the stable horizon, as in the methods tables).";
    table.columns = {"stage", "method", "train RMSE", "test RMSE", "train E_el ratio", "test E_el ratio",
                     "train residual", "test residual", "train BC (m)", "test BC (m)", "frames (train/test)"};
    for (const DiagnosisRow& r : m_rows) {
        std::string method = r.method.empty() ? "—" : r.method;
        if (r.stable_horizon >= 0) method += " (stable " + std::to_string(r.stable_horizon) + ")";
        table.add_row({r.stage, method, number(r.train.rmse), number(r.test.rmse), number(r.train.elastic_ratio),
                       number(r.test.elastic_ratio), number(r.train.residual), number(r.test.residual),
                       number(r.train.bc_violation), number(r.test.bc_violation),
                       std::to_string(r.train.frames) + " / " + std::to_string(r.test.frames)});
    }
    table.add_provenance();
    return table;
}

} // namespace lb
