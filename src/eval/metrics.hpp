#pragma once
// Per-frame metrics of a rollout against ground truth (DESIGN §6). L is the
// rest bounding-box diagonal; x̂ the prediction, x the ground truth, both 3N;
// B the Dirichlet vertices, F the free DOFs, h the time step.
//   rmse            sqrt(mean_i |x̂_i − x_i|²) / L                      (relative position RMSE)
//   bc_violation    max_{i∈B} |x̂_i − x*_i| (m)
//   kinetic         ½ Σ_i m_i |(x̂_i,t − x̂_i,t−1)/h|² (J), all vertices, lab frame; _gt the same
//                   for the ground truth
//   kinetic_free    ½ Σ_{d∈F} m_d ((x̂_d,t − T_t(x̂_t−1)_d)/h)² (J): the free DOFs' kinetic energy
//                   relative to the boundary's rigid motion T_t, the best rigid fit (Kabsch)
//                   of the ground-truth boundary from t−1 to t (translation only if the
//                   boundary is collinear, identity without a boundary). The prescribed
//                   motion of the Dirichlet set (e.g. the bunny's head) is not counted, nor
//                   the free part carried along rigidly with it. _gt the same for the truth.
//   elastic         E_elastic(x̂_t) (J), and the same for ground truth
//   residual        sqrt(mean_{d∈F} (∂E/∂x_d)²) / (m̄|g|), ∇E = ∇E(x̂_t; x̂_{t−1}, x̂_{t−2}) the
//                   implicit-Euler incremental potential with the Dirichlet DOFs excluded:
//                   the per-DOF RMS force imbalance relative to the weight of a mean vertex
//                   (Tan et al.'s M_phys analogue; m̄ L/h² replaces m̄|g| without gravity).
//                   Independent of N, so comparable across scenes.
//   sted_spatial    Vasa & Skala 2011's spatial STED term on one frame: for every vertex v,
//                   the weighted standard deviation of the relative edge-length differences
//                   ed_e = | |ê_e| − |e_e| | / |e_e| over the edges e incident to v (1-ring
//                   neighbourhood), weights |e_e| (ground-truth lengths),
//                     dev_v = sqrt(Σ_e w_e (ed_e − ēd_v)² / Σ_e w_e),  ēd_v = Σ_e w_e ed_e / Σ_e w_e,
//                   averaged over the vertices that have edges.
//   sted_temporal   the temporal term: for every vertex, the difference of the relative speeds
//                   |s̃_v − s_v|, s_v = |x_v,t − x_v,t−1| / l̄_v (displacement per frame in units
//                   of the mean ground-truth length l̄_v of the edges at v at frame t; the same
//                   l̄_v for the prediction), averaged over the vertices.
//   Over frames:   STED = sqrt(STED_s² + c² STED_t²), STED_s and STED_t the means of the two
//                   columns, c = kStedTemporalWeight: the combination of Vasa & Skala 2011
//                   (hypotenuse of the spatial and temporal parts). Our neighbourhoods are the
//                   1-ring (theirs are a parameter), so values are comparable within this
//                   harness, not with the paper's numbers.
// Summaries: see summarize() below and eval/summary_schema.hpp.
#include <string>
#include <vector>

#include "core/rigid_motion.hpp"
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
    X(kKineticFree,      "kinetic_free",      "J")      \
    X(kKineticFreeGt,    "kinetic_free_gt",   "J")      \
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

/// The tiers of the stable horizon (relative RMSE, i.e. fractions of L). A frame
/// "blows up" if its state is non-finite or its RMSE exceeds kBlowupRmse; the stable
/// horizon is the first such frame, and errors are aggregated only before it. The
/// looser tiers are reported as horizons and fractions of frames above them.
constexpr double kBlowupRmse = 0.5;
constexpr double kLooseRmse = 0.1;
constexpr double kTightRmse = 0.02;
/// c in STED = sqrt(STED_s² + c² STED_t²) (Vasa & Skala 2011).
constexpr double kStedTemporalWeight = 0.5;

class MetricContext {
public:
    explicit MetricContext(const PhysicsModel& model);

    /// Fill the metric columns (not the timings) of frame t into `row`. A non-finite
    /// prediction fills the predicted columns with NaN and the ground-truth ones as usual.
    /// @param x, x_prev, x_prev2  predicted frames t, t−1, t−2 (3N)
    /// @param gt, gt_prev         ground-truth frames t, t−1
    /// @param bc_targets          prescribed Dirichlet positions at t (3B)
    void frame_metrics(const VectorXd& x, const VectorXd& x_prev, const VectorXd& x_prev2, const VectorXd& gt,
                       const VectorXd& gt_prev, const VectorXd& bc_targets, Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row);

    /// The ground-truth columns only (kinetic_gt, kinetic_free_gt, elastic_gt) of frame t;
    /// the other metric columns are left as they are (for the frames after a rollout stopped).
    void ground_truth_metrics(const VectorXd& gt, const VectorXd& gt_prev,
                              Eigen::Ref<Eigen::RowVectorXd, 0, Eigen::InnerStride<>> row) const;

    /// Kinetic energy of the free DOFs relative to the boundary's rigid motion from
    /// `bc_from_prev` (frame t−1) to `bc_from` (frame t), both ground truth (J).
    /// @param x, x_prev  the frames t and t−1 whose energy is measured (3N)
    double free_kinetic_energy(const VectorXd& x, const VectorXd& x_prev, const VectorXd& bc_from,
                               const VectorXd& bc_from_prev) const;

    /// The two STED terms of one frame (see the header comment): {spatial, temporal}.
    std::pair<double, double> sted_terms(const VectorXd& x, const VectorXd& x_prev, const VectorXd& gt,
                                         const VectorXd& gt_prev) const;

    double length_scale() const { return m_model.length_scale(); }
    /// m̄|g| (N), or m̄ L/h² without gravity: the force unit of the residual.
    double residual_scale() const { return m_residual_scale; }

private:
    const PhysicsModel& m_model;
    IncrementalPotential m_potential;  ///< hard BC (no penalty): the full-space objective
    VectorXi m_free;                   ///< free DOF indices
    VectorXd m_free_mass;              ///< lumped mass of each free DOF's vertex (kg)
    MatrixXi m_edges;                  ///< unique mesh edges (E×2)
    std::vector<std::vector<int>> m_vertex_edges;  ///< per vertex, the indices of its edges
    double m_residual_scale = 1.0;
};

/// Summarise a T × kNumMetricColumns table (frames 0, 1 are the given start frames):
///  - horizons: the first frame t ≥ 2 above each tier (non-finite counts as above; T if
///    none); stable_horizon is the blow-up tier;
///  - the training window (frames 2 … train_frames−1) and the test window (frames ≥
///    train_frames, and ≥ 2) apart: fractions of their frames above each tier, and the
///    errors (RMSE, boundary violation, KE ratio of kinetic_free, residual, STED, M_rms)
///    aggregated over their frames before the stable horizon only (NaN if none);
///  - timings: medians over the stepped frames after `warmup_frames`.
RolloutSummary summarize(const MatrixXd& metrics, double length_scale, int train_frames, int warmup_frames = 10);

/// Unique undirected edges of the elements (rod edges, triangle or tet edges).
MatrixXi unique_edges(const MatrixXi& elements);

} // namespace lb
