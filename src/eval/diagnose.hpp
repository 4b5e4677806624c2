#pragma once
// The error decomposition of a latent method on one scene (issue 14, `latentbench
// diagnose`): where the rollout error of a reduced method comes from, stage by stage, so
// "under-trained" can be told from "cannot be represented". Every stage is measured on
// the ground-truth frames t ≥ 2 of the chosen sequences, every `stride`-th frame, with
// the metrics of eval/metrics.hpp (RMSE relative to the rest bounding-box diagonal L;
// residual = per-DOF RMS of the full-space step gradient over the free DOFs / m̄|g|),
// averaged separately over the training window (t < train_frames) and the test window:
//
//   ground truth      x_t itself: its residual is the simulator's convergence level
//                     (the floor every other residual is read against)
//   (a) projection    x̂_t = D(E(x_t)): RMSE is the autoencoder's projection error
//   (b) stored energy the same x̂_t with the true history x_{t−1}, x_{t−2}: E_el(x̂_t) / E_el(x_t)
//                     (elastic energy the projection adds or removes), the residual of
//                     x̂_t (the spurious force of the projection, in vertex weights) and
//                     the Dirichlet violation max_B |x̂_i − x*_i|
//   (c) manifold-optimal step
//                     a `fulton_full` integrator: from the encoded truth of t−1, t−2 it
//                     minimises the exact step potential over z; its one-step error is
//                     the best any integrator in this latent space can do in one step
//   (d) one step      any other fitted integrator, reset to the truth of t−2, t−1 and
//                     stepped once: its one-step error beside (c)'s
//   (e) rollout       the method's whole rollout (from its rollout file): mean RMSE of the
//                     windows up to the stable horizon, as in the methods tables
// Read down the rows: if (a) is already large, or (b)'s residual is many vertex weights,
// the subspace cannot represent the motion (more integrator training will not help); if
// (c) is small but (d) is not, the integrator is under-trained or mis-specified; if (d)
// is small but (e) is not, errors accumulate over the rollout (stability).
#include <memory>
#include <string>
#include <vector>

#include "eval/rollout.hpp"
#include "integrators/integrator.hpp"
#include "io/table.hpp"
#include "sim/dataset.hpp"

namespace lb {

class Autoencoder;
class PhysicsModel;

/// Means over the frames of one window (NaN if the window has no frame).
struct DiagnosisWindow {
    int frames = 0;
    double rmse = 0.0;
    double elastic_ratio = 0.0;  ///< mean E_el(x̂) / mean E_el(x) over the window's frames
    double residual = 0.0;
    double bc_violation = 0.0;   ///< max over the frames (m)
};

struct DiagnosisRow {
    std::string stage;   ///< "ground truth", "(a) projection", ...
    std::string method;  ///< the integrator's label ("" for the data and projection rows)
    DiagnosisWindow train, test;
    /// (e) only: stable horizon (blow-up tier), frames, of the worst sequence.
    int stable_horizon = -1;
};

struct DiagnoseOptions {
    std::vector<size_t> sequences;  ///< indices into the dataset (empty: all)
    int stride = 1;                 ///< every stride-th frame t ≥ 2
};

/// Whether a method's one step from the encoded truth is the manifold-optimal step (c):
/// `fulton_full` minimises the exact step potential over z.
bool gives_manifold_optimal_step(const std::string& method_name);
/// The stage a method's one-step row fills: "(c) manifold-optimal step" or "(d) one step".
std::string one_step_stage(const std::string& method_name);

class Diagnosis {
public:
    Diagnosis(const PhysicsModel& model, const Dataset& data, DiagnoseOptions options);

    /// The ground-truth, (a) and (b) rows of an autoencoder.
    void add_autoencoder(Autoencoder& autoencoder);
    /// One row of one-step errors from the truth; `stage` is "(c) manifold-optimal step"
    /// for a fulton_full integrator, "(d) one step" otherwise. A step that fails (throws
    /// NumericalError) or returns a non-finite state counts as RMSE inf for its frame.
    void add_one_step(Integrator& integrator, const std::string& stage);
    /// (e): the windows' mean RMSE of a method's rollouts (worst stable horizon), from
    /// the summaries of its sequences that this diagnosis covers.
    void add_rollout(const std::vector<RolloutRecord>& records);

    const std::vector<DiagnosisRow>& rows() const { return m_rows; }
    /// The table: one row per stage and method, train and test columns.
    Table table(const std::string& scene_name) const;

private:
    /// Frames (sequence, t) measured, in order.
    struct FrameRef {
        size_t sequence;
        Index t;
    };
    const PhysicsModel& m_model;
    const Dataset& m_data;
    DiagnoseOptions m_options;
    std::vector<FrameRef> m_frames;
    std::vector<DiagnosisRow> m_rows;
};

} // namespace lb
