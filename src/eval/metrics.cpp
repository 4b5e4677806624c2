#include "eval/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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
    m_free_mass.resize(m_free.size());
    for (Index k = 0; k < m_free.size(); ++k) m_free_mass[k] = model.masses()[m_free[k] / 3];
    m_edges = unique_edges(model.mesh().elements);
    m_vertex_edges.assign(size_t(model.num_vertices()), {});
    for (Index e = 0; e < m_edges.rows(); ++e) {
        m_vertex_edges[size_t(m_edges(e, 0))].push_back(int(e));
        m_vertex_edges[size_t(m_edges(e, 1))].push_back(int(e));
    }
    const double mean_mass = model.num_vertices() > 0 ? model.masses().mean() : 1.0;
    const double g = model.spec().gravity.norm();
    m_residual_scale = mean_mass * (g > 0.0 ? g : model.length_scale() / (model.dt() * model.dt()));
}

double MetricContext::free_kinetic_energy(const VectorXd& x, const VectorXd& x_prev, const VectorXd& bc_from,
                                          const VectorXd& bc_from_prev) const
{
    const auto& bc = m_model.bc_indices();
    MatrixX3d from(Index(bc.size()), 3), to(Index(bc.size()), 3);
    for (size_t b = 0; b < bc.size(); ++b) {
        from.row(Index(b)) = bc_from_prev.segment<3>(3 * bc[b]).transpose();
        to.row(Index(b)) = bc_from.segment<3>(3 * bc[b]).transpose();
    }
    const RigidMotion motion = fit_rigid_motion(from, to);
    const double inv_h = 1.0 / m_model.dt();
    double e = 0.0;
    for (Index k = 0; k < m_free.size(); ++k) {
        const Index d = m_free[k], i = d / 3, c = d % 3;
        const double carried = motion.apply(x_prev.segment<3>(3 * i))[c];
        e += 0.5 * m_free_mass[k] * std::pow((x[d] - carried) * inv_h, 2);
    }
    return e;
}

std::pair<double, double> MetricContext::sted_terms(const VectorXd& x, const VectorXd& x_prev, const VectorXd& gt,
                                                    const VectorXd& gt_prev) const
{
    const Index E = m_edges.rows();
    VectorXd length_gt(E), relative_difference(E);
    for (Index e = 0; e < E; ++e) {
        const int i = m_edges(e, 0), j = m_edges(e, 1);
        const double lp = (x.segment<3>(3 * i) - x.segment<3>(3 * j)).norm();
        const double lg = (gt.segment<3>(3 * i) - gt.segment<3>(3 * j)).norm();
        length_gt[e] = std::max(lg, 1e-300);
        relative_difference[e] = std::abs(lp - lg) / length_gt[e];
    }
    double spatial = 0.0, temporal = 0.0;
    Index counted = 0;
    for (size_t v = 0; v < m_vertex_edges.size(); ++v) {
        const auto& edges = m_vertex_edges[v];
        if (edges.empty()) continue;
        double w_sum = 0.0, mean = 0.0;
        for (int e : edges) {
            w_sum += length_gt[e];
            mean += length_gt[e] * relative_difference[e];
        }
        mean /= w_sum;
        double var = 0.0;
        for (int e : edges) var += length_gt[e] * std::pow(relative_difference[e] - mean, 2);
        spatial += std::sqrt(var / w_sum);
        const double local_length = w_sum / double(edges.size());
        const Index i = Index(v);
        const double sp = (x.segment<3>(3 * i) - x_prev.segment<3>(3 * i)).norm() / local_length;
        const double sg = (gt.segment<3>(3 * i) - gt_prev.segment<3>(3 * i)).norm() / local_length;
        temporal += std::abs(sp - sg);
        ++counted;
    }
    if (counted == 0) return {0.0, 0.0};
    return {spatial / double(counted), temporal / double(counted)};
}

void MetricContext::ground_truth_metrics(const VectorXd& gt, const VectorXd& gt_prev,
                                         Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row) const
{
    row[kKineticGt] = m_model.kinetic_energy(gt, gt_prev);
    row[kKineticFreeGt] = free_kinetic_energy(gt, gt_prev, gt, gt_prev);
    row[kElasticGt] = m_model.elastic_energy(gt);
}

void MetricContext::frame_metrics(const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2,
                                  const VectorXd& gt, const VectorXd& gt_prev, const VectorXd& bc_targets,
                                  Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double L = m_model.length_scale();
    const Index N = m_model.num_vertices();
    ground_truth_metrics(gt, gt_prev, row);
    if (!x.allFinite()) {
        for (int c : {kRmse, kBcViolation, kKinetic, kKineticFree, kElastic, kResidual, kStedSpatial, kStedTemporal})
            row[c] = nan;
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
    row[kKineticFree] = free_kinetic_energy(x, x_prev, gt, gt_prev);
    row[kElastic] = m_model.elastic_energy(x);
    m_potential.set_previous(x_prev, x_prev2);
    const VectorXd g = m_potential.gradient(x);
    const double rms = m_free.size() > 0 ? std::sqrt(g(m_free).squaredNorm() / double(m_free.size())) : 0.0;
    row[kResidual] = rms / m_residual_scale;
    const auto [spatial, temporal] = sted_terms(x, x_prev, gt, gt_prev);
    row[kStedSpatial] = spatial;
    row[kStedTemporal] = temporal;
}

namespace {

/// Median of the finite entries (NaN if none).
double finite_median(const std::vector<double>& values)
{
    std::vector<double> v;
    for (double x : values) {
        if (std::isfinite(x)) v.push_back(x);
    }
    if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
    std::nth_element(v.begin(), v.begin() + long(v.size() / 2), v.end());
    return v[v.size() / 2];
}

/// A frame is above a tier if its RMSE exceeds it or is not finite.
bool above(double rmse, double tier) { return !(rmse <= tier); }

/// The first frame t ≥ 2 above `tier`, T if none.
int first_above(const MatrixXd& metrics, double tier)
{
    for (Index t = 2; t < metrics.rows(); ++t) {
        if (above(metrics(t, kRmse), tier)) return int(t);
    }
    return int(metrics.rows());
}

/// Frames [begin, end) of one window; errors over [begin, min(end, horizon)).
SummaryWindow summarize_window(const MatrixXd& metrics, double length_scale, Index begin, Index end, Index horizon)
{
    const double nan = std::numeric_limits<double>::quiet_NaN();
    SummaryWindow w;
    w.window_frames = int(std::max<Index>(end - begin, 0));
    const Index stop = std::max(begin, std::min(end, horizon));
    w.evaluated_frames = int(stop - begin);
    int blowup = 0, loose = 0, tight = 0;
    for (Index t = begin; t < end; ++t) {
        const double rmse = metrics(t, kRmse);
        blowup += above(rmse, kBlowupRmse);
        loose += above(rmse, kLooseRmse);
        tight += above(rmse, kTightRmse);
    }
    const double n_window = double(w.window_frames);
    w.frac_blowup = w.window_frames > 0 ? blowup / n_window : nan;
    w.frac_loose = w.window_frames > 0 ? loose / n_window : nan;
    w.frac_tight = w.window_frames > 0 ? tight / n_window : nan;
    w.mean_rmse = w.final_rmse = w.max_bc_violation = w.ke_ratio = w.mean_residual = w.m_rms = w.sted = nan;
    if (w.evaluated_frames == 0) return w;
    double sum_rmse = 0.0, sum_sq = 0.0, ke = 0.0, ke_gt = 0.0, residual = 0.0, spatial = 0.0, temporal = 0.0;
    double max_bc = 0.0;
    for (Index t = begin; t < stop; ++t) {
        sum_rmse += metrics(t, kRmse);
        sum_sq += std::pow(metrics(t, kRmse) * length_scale, 2);
        max_bc = std::max(max_bc, metrics(t, kBcViolation));
        ke += metrics(t, kKineticFree);
        ke_gt += metrics(t, kKineticFreeGt);
        residual += metrics(t, kResidual);
        spatial += metrics(t, kStedSpatial);
        temporal += metrics(t, kStedTemporal);
    }
    const double n = double(w.evaluated_frames);
    w.mean_rmse = sum_rmse / n;
    w.final_rmse = metrics(stop - 1, kRmse);
    w.max_bc_violation = max_bc;
    w.ke_ratio = ke_gt > 0.0 ? ke / ke_gt : nan;  // no ground-truth motion: undefined, not 0
    w.mean_residual = residual / n;
    w.m_rms = std::sqrt(sum_sq / n);
    w.sted = std::hypot(spatial / n, kStedTemporalWeight * temporal / n);
    return w;
}

} // namespace

RolloutSummary summarize(const MatrixXd& metrics, double length_scale, int train_frames, int warmup_frames)
{
    RolloutSummary s;
    const Index T = metrics.rows();
    s.frames = int(T);
    s.train_frames = train_frames;
    s.sequences = 1;
    s.stable_horizon = first_above(metrics, kBlowupRmse);
    s.horizon_loose = first_above(metrics, kLooseRmse);
    s.horizon_tight = first_above(metrics, kTightRmse);
    const Index split = std::clamp<Index>(train_frames, 2, std::max<Index>(T, 2));
    s.train = summarize_window(metrics, length_scale, 2, split, s.stable_horizon);
    s.test = summarize_window(metrics, length_scale, split, T, s.stable_horizon);
    // Timings of the frames that were stepped (finite), after warm-up if there are any.
    for (const Index first : {Index(2 + warmup_frames), Index(2)}) {
        std::vector<double> integ, dec, tot;
        for (Index t = first; t < T; ++t) {
            const double a = metrics(t, kIntegrateSeconds), b = metrics(t, kDecodeSeconds);
            if (!std::isfinite(a + b)) continue;
            integ.push_back(a);
            dec.push_back(b);
            tot.push_back(a + b);
        }
        s.integrate_ms = 1e3 * finite_median(integ);
        s.decode_ms = 1e3 * finite_median(dec);
        s.total_ms = 1e3 * finite_median(tot);
        if (!tot.empty()) break;
    }
    return s;
}

} // namespace lb
