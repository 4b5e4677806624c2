#pragma once
// The stability regression gate (`latentbench regress`): the metric tables of a
// finished run against those of a baseline (a published results/ folder, or an
// earlier run). Rows are matched by scene, method, sweep point and window; each
// gated metric of a row is classified against the baseline's range over seeds,
// widened by a tolerance:
//
//   band = [lo − (|lo|·relative + absolute), hi + (|hi|·relative + absolute)]
//   lo, hi = the smallest and largest of the baseline's per-seed values (finite ones)
//   now    = the median of the run's per-seed values (finite ones)
//
// A lower-is-better metric (an error) regresses when now > band's top and improves
// when now < band's bottom; a higher-is-better one (a horizon) the other way round.
// A finite baseline against a run without a finite value (no frames before a blow-up)
// regresses; the reverse improves. Divergence is its own check: a row regresses when
// a larger share of its seeds blew up than in the baseline ("newly diverged").
//
// Input: per scene the tidy `rollouts_<scene>.csv` that `latentbench run` writes
// (one row per method, sweep point, seed, sequence and window); a folder written
// before those existed is read through its `methods_<scene>.csv` instead, one
// observation per row (the table's value: with seeds the median, so the range
// collapses to it, and only the shown metrics).
#include <map>
#include <string>
#include <vector>

namespace lb {

/// One gated metric and its tolerance (the defaults: default_gate_metrics()).
struct GateMetric {
    std::string field;              ///< summary metric field (eval/summary_schema.hpp), e.g. "mean_rmse"
    bool higher_is_better = false;  ///< true for horizons (frames)
    double relative = 0.0;          ///< widening of the baseline's seed range, relative to its ends
    double absolute = 0.0;          ///< and in the metric's unit (frames, m, or relative RMSE)
};

struct GateOptions {
    std::vector<GateMetric> metrics;
    /// Whether a share of diverged seeds larger than the baseline's fails the row.
    bool check_divergence = true;
    /// A row of the baseline that the run lacks fails the gate (default: reported only).
    bool fail_on_missing = false;
};

/// The defaults, written in README ("Regression gate"): stable_horizon (higher is
/// better, 0 frames), horizon_loose (higher, 10 %), mean_rmse (lower, 25 % + 1e-4),
/// final_rmse (lower, 50 % + 1e-4), max_bc_violation (lower, 50 % + 1e-4 m).
std::vector<GateMetric> default_gate_metrics();
GateOptions default_gate_options();

/// A tolerance file (TOML) over the defaults:
///   fail_on_missing = false
///   check_divergence = true
///   [metrics.mean_rmse]           # any summary metric with a direction: horizons
///   relative = 0.25               # (stable_horizon, horizon_loose, horizon_tight) and the
///   absolute = 1.0e-4             # errors (final_rmse, mean_rmse, max_bc_violation,
///   gate = true                   # ke_ratio, mean_residual, sted); gate = false drops it
/// Unknown keys and metrics are ConfigErrors naming the key and the file.
GateOptions load_gate_options(const std::string& path);

/// Table rows are matched on this.
struct GateRowKey {
    std::string scene, method, point, window;  ///< point "" without a [sweep]; window "train" or "test"
    bool operator<(const GateRowKey& o) const;
    bool operator==(const GateRowKey& o) const;
    std::string text() const;  ///< "cloth_small / ours / test" (with the point if any)
};

/// A row of a run: per metric field, one value per seed (aggregated over the seed's
/// sequences as the methods tables do), and how many of the seeds diverged.
struct GateRow {
    GateRowKey key;
    std::map<std::string, std::vector<double>> values;  ///< field -> per-seed values
    int seeds = 0;
    int diverged = 0;
    std::string source;  ///< the file it was read from
};

/// Every row of a run or results folder: DIR/tables/ if it exists, else DIR itself.
/// IoError naming the folder if it holds no rollouts_*.csv nor methods_*.csv,
/// and naming the file (and line) if one is malformed.
std::vector<GateRow> load_gate_rows(const std::string& dir);

enum class GateVerdict { Unchanged, Improvement, Regression, Missing, New };
const char* to_string(GateVerdict v);

/// One metric of one row (or the divergence check, field "diverged").
struct GateMetricResult {
    std::string field;
    GateVerdict verdict = GateVerdict::Unchanged;
    std::string baseline;  ///< "0.0108" or "0.0108 [0.0101, 0.0113] (3 seeds)"
    std::string now;
    std::string change;    ///< "+12.3 %", "-300 frames", "0/3 -> 2/3 seeds diverged"
    std::string reason;    ///< why a verdict other than unchanged: "above the band's top 0.0135"
};

struct GateRowResult {
    GateRowKey key;
    GateVerdict verdict = GateVerdict::Unchanged;  ///< the worst of its metrics (or missing/new)
    std::vector<GateMetricResult> metrics;
};

struct GateReport {
    std::vector<GateRowResult> rows;  ///< ordered by key
    GateOptions options;
    int count(GateVerdict v) const;
    /// Any regression (or, with fail_on_missing, any missing row): exit code 1.
    bool failed() const;
};

GateReport compare_gate_rows(const std::vector<GateRow>& baseline, const std::vector<GateRow>& now,
                             const GateOptions& options);

} // namespace lb
