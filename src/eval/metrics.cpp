#include "eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace lb {

const std::vector<MetricColumnInfo>& metric_columns()
{
    static const std::vector<MetricColumnInfo> columns{
#define LB_METRIC_COLUMN_INFO(id, name, unit) {name, unit},
        LB_METRIC_COLUMNS(LB_METRIC_COLUMN_INFO)
#undef LB_METRIC_COLUMN_INFO
    };
    return columns;
}

const std::vector<std::string>& metric_column_names()
{
    static const std::vector<std::string> names = [] {
        std::vector<std::string> out;
        for (const auto& c : metric_columns()) out.emplace_back(c.name);
        return out;
    }();
    return names;
}

MatrixXi unique_edges(const MatrixXi& elements)
{
    std::set<std::pair<int, int>> edges;
    for (Index e = 0; e < elements.rows(); ++e) {
        for (Index a = 0; a < elements.cols(); ++a) {
            for (Index b = a + 1; b < elements.cols(); ++b) {
                const int i = elements(e, a), j = elements(e, b);
                edges.insert({std::min(i, j), std::max(i, j)});
            }
        }
    }
    MatrixXi out(Index(edges.size()), 2);
    Index k = 0;
    for (const auto& [i, j] : edges) out.row(k++) << i, j;
    return out;
}

MetricContext::MetricContext(const PhysicsModel& model) : m_model(model), m_potential(model, 0.0)
{
    const VectorXi map = model.dof_to_unknown();
    std::vector<int> free;
    for (Index d = 0; d < map.size(); ++d) {
        if (map[d] >= 0) free.push_back(int(d));
    }
    m_free = Eigen::Map<VectorXi>(free.data(), Index(free.size()));
    m_edges = unique_edges(model.mesh().elements);
    double sum = 0.0;
    for (Index e = 0; e < m_edges.rows(); ++e) {
        sum += (model.mesh().rest_positions.row(m_edges(e, 0)) - model.mesh().rest_positions.row(m_edges(e, 1))).norm();
    }
    m_mean_edge = m_edges.rows() ? sum / double(m_edges.rows()) : 1.0;
}

void MetricContext::frame_metrics(const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2,
                                  const VectorXd& gt, const VectorXd& gt_prev, const VectorXd& bc_targets,
                                  Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double L = m_model.length_scale();
    const double h = m_model.dt();
    const Index N = m_model.num_vertices();
    if (!x.allFinite()) {
        row.head(kIntegrateSeconds).setConstant(nan);
        row[kKineticGt] = m_model.kinetic_energy(gt, gt_prev);
        row[kElasticGt] = m_model.elastic_energy(gt);
        return;
    }
    row[kRmse] = std::sqrt((x - gt).squaredNorm() / double(N)) / L;
    double violation = 0.0;
    const auto& bc = m_model.bc_indices();
    for (size_t b = 0; b < bc.size(); ++b) {
        violation = std::max(violation, (x.segment<3>(3 * bc[b]) - bc_targets.segment<3>(3 * Index(b))).norm());
    }
    row[kBcViolation] = violation;
    row[kKinetic] = m_model.kinetic_energy(x, x_prev);
    row[kKineticGt] = m_model.kinetic_energy(gt, gt_prev);
    row[kElastic] = m_model.elastic_energy(x);
    row[kElasticGt] = m_model.elastic_energy(gt);
    m_potential.set_previous(x_prev, x_prev2);
    const VectorXd g = m_potential.gradient(x);
    row[kResidual] = g(m_free).norm() / m_model.force_scale();

    double spatial = 0.0;
    for (Index e = 0; e < m_edges.rows(); ++e) {
        const int i = m_edges(e, 0), j = m_edges(e, 1);
        const double lp = (x.segment<3>(3 * i) - x.segment<3>(3 * j)).norm();
        const double lg = (gt.segment<3>(3 * i) - gt.segment<3>(3 * j)).norm();
        spatial += std::pow((lp - lg) / std::max(lg, 1e-12), 2);
    }
    row[kStedSpatial] = std::sqrt(spatial / double(std::max<Index>(m_edges.rows(), 1)));
    double temporal = 0.0;
    const double speed_unit = m_mean_edge / h;
    for (Index i = 0; i < N; ++i) {
        const double vp = (x.segment<3>(3 * i) - x_prev.segment<3>(3 * i)).norm() / h;
        const double vg = (gt.segment<3>(3 * i) - gt_prev.segment<3>(3 * i)).norm() / h;
        temporal += std::pow((vp - vg) / speed_unit, 2);
    }
    row[kStedTemporal] = std::sqrt(temporal / double(N));
}

namespace {
double median(std::vector<double> v)
{
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}
} // namespace

RolloutSummary summarize(const MatrixXd& metrics, double length_scale, int warmup_frames)
{
    RolloutSummary s;
    const Index T = metrics.rows();
    s.frames = int(T);
    s.stable_horizon = int(T);
    for (Index t = 2; t < T; ++t) {
        const double rmse = metrics(t, kRmse);
        const double bc = metrics(t, kBcViolation) / length_scale;
        if (!std::isfinite(rmse) || rmse > kUnstableRmse || !std::isfinite(bc) || bc > kUnstableBcViolation) {
            s.stable_horizon = int(t);
            break;
        }
    }
    // Error summaries over the predicted frames (2..T−1); non-finite frames count as such.
    double sum_rmse = 0.0, sum_sq = 0.0, ke = 0.0, ke_gt = 0.0, residual = 0.0, sted = 0.0;
    s.max_bc_violation = 0.0;
    const Index n = std::max<Index>(T - 2, 1);
    for (Index t = 2; t < T; ++t) {
        sum_rmse += metrics(t, kRmse);
        sum_sq += std::pow(metrics(t, kRmse) * length_scale, 2);
        s.max_bc_violation = std::max(s.max_bc_violation, metrics(t, kBcViolation));
        if (std::isnan(metrics(t, kBcViolation))) s.max_bc_violation = metrics(t, kBcViolation);
        ke += metrics(t, kKinetic);
        ke_gt += metrics(t, kKineticGt);
        residual += metrics(t, kResidual);
        sted += metrics(t, kStedSpatial) + 0.5 * metrics(t, kStedTemporal);
    }
    s.final_rmse = metrics(T - 1, kRmse);
    s.mean_rmse = sum_rmse / double(n);
    s.m_rms = std::sqrt(sum_sq / double(n));
    s.ke_ratio = ke_gt > 0.0 ? ke / ke_gt : 0.0;
    s.mean_residual = residual / double(n);
    s.sted = sted / double(n);
    std::vector<double> integ, dec, tot;
    for (Index t = 2 + warmup_frames; t < T; ++t) {
        integ.push_back(metrics(t, kIntegrateSeconds));
        dec.push_back(metrics(t, kDecodeSeconds));
        tot.push_back(metrics(t, kIntegrateSeconds) + metrics(t, kDecodeSeconds));
    }
    if (integ.empty()) {
        for (Index t = 2; t < T; ++t) {
            integ.push_back(metrics(t, kIntegrateSeconds));
            dec.push_back(metrics(t, kDecodeSeconds));
            tot.push_back(metrics(t, kIntegrateSeconds) + metrics(t, kDecodeSeconds));
        }
    }
    s.integrate_ms = 1e3 * median(integ);
    s.decode_ms = 1e3 * median(dec);
    s.total_ms = 1e3 * median(tot);
    return s;
}

} // namespace lb
