#pragma once
// Per-frame metrics of a rollout against ground truth (DESIGN §6). L is the
// rest bounding-box diagonal; x̂ the prediction, x the ground truth, both 3N.
//   rmse          sqrt(mean_i |x̂_i − x_i|²) / L                       (relative position RMSE)
//   bc_violation  max_{i∈B} |x̂_i − x*_i| (m)
//   kinetic       ½ Σ m_i |(x̂_i,t − x̂_i,t−1)/h|² (J), and the same for ground truth
//   elastic       E_elastic(x̂_t) (J), and the same for ground truth
//   residual      ||∇E(x̂_t; x̂_{t−1}, x̂_{t−2})|| over the free DOFs / force scale
//                 (Tan et al.'s M_phys, with Dirichlet DOFs excluded, dimensionless)
//   sted_spatial  sqrt(mean_e ((|ê_e| − |e_e|)/|e_e|)²): relative edge-length deviation
//   sted_temporal sqrt(mean_i ((|v̂_i| − |v_i|)/(ē/h))²): vertex-speed difference relative
//                 to the speed of one mean rest edge length per step
//   STED = sted_spatial + 0.5 · sted_temporal  (the weighting of Vasa & Skala 2011's
//   spatial and temporal terms; our terms are simplified: global, not per-vertex-neighbourhood)
// Summaries (RolloutSummary; the list of them is eval/summary_schema.hpp):
// stable horizon = frames until a non-finite state, rmse > 0.5 or bc_violation / L > 0.1; M_rms = RMS vertex error over all frames (m, unscaled);
// KE ratio = Σ_t KE_pred / Σ_t KE_gt.
#include <string>
#include <vector>

#include "eval/summary_schema.hpp"
#include "sim/physics_model.hpp"

namespace lb {

// Per-frame metric columns, one line each: enumerator, HDF5/CSV name, unit ("" if
// dimensionless). To add a column, add one line here and fill it in frame_metrics().
// clang-format off
#define LB_METRIC_COLUMNS(X)                            \
    X(kRmse,             "rmse",              "")       \
    X(kBcViolation,      "bc_violation",      "m")      \
    X(kKinetic,          "kinetic",           "J")      \
    X(kKineticGt,        "kinetic_gt",        "J")      \
    X(kElastic,          "elastic",           "J")      \
    X(kElasticGt,        "elastic_gt",        "J")      \
    X(kResidual,         "residual",          "")       \
    X(kStedSpatial,      "sted_spatial",      "")       \
    X(kStedTemporal,     "sted_temporal",     "")       \
    X(kIntegrateSeconds, "integrate_seconds", "s")      \
    X(kDecodeSeconds,    "decode_seconds",    "s")
// clang-format on

enum MetricColumn {
#define LB_METRIC_COLUMN_ENUM(id, name, unit) id,
    LB_METRIC_COLUMNS(LB_METRIC_COLUMN_ENUM)
#undef LB_METRIC_COLUMN_ENUM
    kNumMetricColumns
};
struct MetricColumnInfo {
    const char* name;  ///< as written to HDF5/CSV
    const char* unit;  ///< "" if dimensionless
};
/// Every per-frame column, indexed by MetricColumn.
const std::vector<MetricColumnInfo>& metric_columns();
/// Column names as written to HDF5/CSV.
const std::vector<std::string>& metric_column_names();

/// Stability thresholds of the stable horizon (relative to L).
constexpr double kUnstableRmse = 0.5;
constexpr double kUnstableBcViolation = 0.1;

class MetricContext {
public:
    explicit MetricContext(const PhysicsModel& model);

    /// Fill the metric columns (not the timings) of frame t into `row`.
    /// @param x, x_prev, x_prev2  predicted frames t, t−1, t−2 (3N)
    /// @param gt, gt_prev         ground-truth frames t, t−1
    /// @param bc_targets          prescribed Dirichlet positions at t (3B)
    void frame_metrics(const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2, const VectorXd& gt,
                       const VectorXd& gt_prev, const VectorXd& bc_targets, Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row);

    double length_scale() const { return m_model.length_scale(); }

private:
    const PhysicsModel& m_model;
    IncrementalPotential m_potential;  ///< hard BC (no penalty): the full-space objective
    VectorXi m_free;                   ///< free DOF indices
    MatrixXi m_edges;                  ///< unique mesh edges (E×2)
    double m_mean_edge = 1.0;
};

/// Summarise a T × kNumMetricColumns table (frames 0, 1 are the given start frames).
RolloutSummary summarize(const MatrixXd& metrics, double length_scale, int warmup_frames = 10);

/// Unique undirected edges of the elements (rod edges, triangle or tet edges).
MatrixXi unique_edges(const MatrixXi& elements);

} // namespace lb
