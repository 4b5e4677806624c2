#pragma once
// The summary metrics of a rollout (DESIGN §6), as ONE list. To add a metric,
// add one line here (and compute it in summarize(), eval/metrics.cpp). The list
// generates the RolloutSummary fields and the schema that drives every place a
// summary is written, read, aggregated or shown: save_rollouts /
// load_rollout_summaries (HDF5 attributes), the aggregation over sequences, the
// comparison tables (Markdown/CSV/LaTeX) and the CLI `rollout`/`evaluate`
// printout. Table columns and printout columns follow the order of the list.
//
// Columns of a line:
//   scope   rollout: one value per rollout (horizons, timings);
//           window: one value per window, the training window (frames 2 … train_frames−1)
//           and the test window (frames ≥ train_frames), fields of RolloutSummary::train
//           and ::test, HDF5 attributes "train_<field>" and "test_<field>"
//   type    int or double (an int is written as a 64-bit integer attribute)
//   field   the member; also its HDF5 attribute (prefixed by the window) and CSV name
//   title   column title in the comparison tables (one row per method and window)
//   unit    SI-style unit, "" if dimensionless (relative metrics, ratios)
//   agg     over sequences: kMean (of the finite values; NaN if none), kMax (of the
//           finite values), kMin (worst case of a "higher is better" count, e.g. a
//           horizon), kSum
//   table   how the comparison table shows it:
//             sig(d)       d significant digits, non-finite as "nan"
//             error(d)     an error aggregated before the stable horizon: d significant
//                          digits, "— (empty)" for an empty window, "diverged @h" if the
//                          rollout blew up before the window, "v (diverged @h)" if inside it
//             cell(fn)     a custom cell, fn(const RolloutSummary&, const SummaryMetric&)
//             hidden()     not in the table
//   cli     cli(header, width, printf conversion taking (width, value)), or no_cli()
//
// timing_threads is the thread count of the process that rolled out (and so timed) the
// sequence, recorded because a table is often written by another process (a merge, a
// cluster job) whose own thread count says nothing about the times; NaN in files written
// before it was recorded.
//
// Definitions of the metrics: eval/metrics.hpp. Times are medians per frame after
// warm-up; M_rms is in metres (unscaled), RMSEs are relative to the rest
// bounding-box diagonal; horizons are frame indices (= frames if never crossed).
#include <string>
#include <vector>

#include "io/table.hpp"

// clang-format off
#define LB_SUMMARY_METRICS(X)                                                                                                         \
  /* scope    type    field              title                 unit      agg    table                  cli                        */ \
    X(rollout, int,    frames,            "frames",             "frames", kMin,  hidden(),              cli("frames", 6, "%*d"))       \
    X(rollout, int,    train_frames,      "training frames",    "frames", kMin,  hidden(),              cli("train", 6, "%*d"))        \
    X(rollout, int,    sequences,         "sequences",          "",       kSum,  hidden(),              no_cli())                      \
    X(rollout, int,    stable_horizon,    "stable (blow-up)",   "frames", kMin,  cell(stable_cell),     cli("stable", 7, "%*d"))       \
    X(rollout, int,    horizon_loose,     "first RMSE > 0.1",   "frames", kMin,  cell(tier_cell),       cli("rmse>0.1", 8, "%*d"))     \
    X(rollout, int,    horizon_tight,     "first RMSE > 0.02",  "frames", kMin,  cell(tier_cell),       cli("rmse>0.02", 9, "%*d"))    \
    X(window,  int,    window_frames,     "window frames",      "frames", kSum,  hidden(),              cli("window", 6, "%*d"))       \
    X(window,  int,    evaluated_frames,  "frames aggregated",  "frames", kSum,  cell(evaluated_cell),  cli("aggr", 6, "%*d"))         \
    X(window,  double, frac_blowup,       "% frames > 0.5",     "",       kMean, cell(percent_cell),    cli("%>0.5", 6, "%*.3g"))      \
    X(window,  double, frac_loose,        "% frames > 0.1",     "",       kMean, cell(percent_cell),    cli("%>0.1", 6, "%*.3g"))      \
    X(window,  double, frac_tight,        "% frames > 0.02",    "",       kMean, cell(percent_cell),    cli("%>0.02", 6, "%*.3g"))     \
    X(window,  double, final_rmse,        "final RMSE",         "",       kMean, error(3),              cli("final_rmse", 10, "%*.4g")) \
    X(window,  double, mean_rmse,         "mean RMSE",          "",       kMean, error(3),              cli("mean_rmse", 10, "%*.4g")) \
    X(window,  double, max_bc_violation,  "max BC viol. (m)",   "m",      kMax,  error(3),              cli("max_bc_m", 10, "%*.4g"))  \
    X(window,  double, ke_ratio,          "KE ratio (free)",    "",       kMean, error(3),              cli("ke_ratio", 8, "%*.3f"))   \
    X(window,  double, mean_residual,     "residual",           "",       kMean, error(3),              cli("residual", 10, "%*.4g"))  \
    X(window,  double, m_rms,             "M_rms (m)",          "m",      kMean, hidden(),              no_cli())                      \
    X(window,  double, sted,              "STED (1-ring)",      "",       kMean, error(3),              cli("sted", 9, "%*.4g"))       \
    X(rollout, double, integrate_ms,      "integrate (ms)",     "ms",     kMean, sig(3),                no_cli())                      \
    X(rollout, double, decode_ms,         "decode (ms)",        "ms",     kMean, sig(3),                no_cli())                      \
    X(rollout, double, total_ms,          "total (ms)",         "ms",     kMean, sig(3),                cli("total_ms", 9, "%*.4f")) \
    X(rollout, double, timing_threads,    "timing threads",     "",       kMax,  hidden(),              no_cli())
// clang-format on

namespace lb {

namespace h5 {
class File;
}

/// The metrics of one window of a rollout (scope "window").
struct SummaryWindow {
#define LB_SUMMARY_FIELD_rollout(type, field)
#define LB_SUMMARY_FIELD_window(type, field) type field = 0;
#define LB_SUMMARY_FIELD(scope, type, field, ...) LB_SUMMARY_FIELD_##scope(type, field)
    LB_SUMMARY_METRICS(LB_SUMMARY_FIELD)
#undef LB_SUMMARY_FIELD
#undef LB_SUMMARY_FIELD_window
#undef LB_SUMMARY_FIELD_rollout
};

struct RolloutSummary {
#define LB_SUMMARY_FIELD_rollout(type, field) type field = 0;
#define LB_SUMMARY_FIELD_window(type, field)
#define LB_SUMMARY_FIELD(scope, type, field, ...) LB_SUMMARY_FIELD_##scope(type, field)
    LB_SUMMARY_METRICS(LB_SUMMARY_FIELD)
#undef LB_SUMMARY_FIELD
#undef LB_SUMMARY_FIELD_window
#undef LB_SUMMARY_FIELD_rollout
    SummaryWindow train;  ///< frames 2 … train_frames−1
    SummaryWindow test;   ///< frames ≥ max(train_frames, 2)
};

/// Which part of a summary a metric belongs to.
enum class SummaryScope { Rollout, Train, Test };
const char* to_string(SummaryScope scope);

/// How a metric combines over the sequences of a method (one table row).
enum class SummaryAggregation {
    Mean,  ///< arithmetic mean of the finite values (NaN if none)
    Max,   ///< largest finite value (NaN if none)
    Min,   ///< worst case of a "higher is better" count, e.g. a horizon
    Sum    ///< total, e.g. frames of a window
};

struct SummaryMetric;
/// Table cell of one metric of a summary (the per-metric formatting hook).
using SummaryCellFn = TableCell (*)(const RolloutSummary& s, const SummaryMetric& metric);

struct SummaryMetric {
    const char* name;   ///< HDF5 attribute and CSV name ("train_"/"test_" + field for a window metric)
    const char* field;  ///< the field name
    SummaryScope scope;
    const char* title;  ///< comparison-table column title
    const char* unit;   ///< "" if dimensionless
    SummaryAggregation aggregation;
    bool integer;  ///< int field (64-bit integer attribute)
    struct Table {
        bool shown = false;
        int digits = 3;               ///< significant digits of the default cell
        SummaryCellFn cell = nullptr; ///< nullptr: `digits` significant digits, non-finite as "nan"
        bool error = false;           ///< aggregated before the stable horizon (annotated if cut)
    } table;
    struct Cli {
        const char* header = nullptr;  ///< nullptr: not printed
        int width = 0;
        const char* format = "";  ///< printf conversion taking (int width, value): "%*d" (int) or e.g. "%*.4g"
    } cli;
    double (*get)(const RolloutSummary&);
    void (*set)(RolloutSummary&, double);  ///< an int field takes the value truncated
};

/// Every summary metric, in the order of LB_SUMMARY_METRICS (a window metric twice:
/// training window, then test window).
const std::vector<SummaryMetric>& summary_metrics();

/// Combine the summaries of several sequences per each metric's aggregation
/// (a default RolloutSummary if `all` is empty).
RolloutSummary aggregate(const std::vector<RolloutSummary>& all);

/// Write every metric as an attribute of `group`.
void write_summary(h5::File& file, const std::string& group, const RolloutSummary& s);
/// Read the attributes written by write_summary. A floating-point metric missing
/// from the file (written before the metric existed) reads as NaN; a missing
/// integer metric throws IoError.
RolloutSummary read_summary(const h5::File& file, const std::string& group);

/// Titles of the metrics the comparison tables show (rollout metrics and one window's),
/// and their cells for one summary and window (SummaryScope::Train or ::Test).
std::vector<std::string> summary_table_columns();
std::vector<TableCell> summary_table_cells(const RolloutSummary& s, SummaryScope window);

/// The same cells over several seeds (one summary per seed, each over its sequences):
/// with n ≥ 5 seeds "mean ± h", h the half-width of the 95 % Student-t interval of the
/// mean; with 2 ≤ n < 5 "median [min, max]"; one seed as summary_table_cells. Errors are
/// over the seeds with aggregated frames; "(k/n diverged @h)" says how many seeds blew
/// up inside the window and the earliest horizon; "diverged @h (all n seeds)" if none has
/// aggregated frames. Horizons count "never" as the frame count.
std::vector<TableCell> summary_table_cells_over_seeds(const std::vector<RolloutSummary>& per_seed, SummaryScope window);

/// The columns of a comparison table's CSV (the machine-readable twin of the Markdown
/// cells): per row `n_seeds` (runs the row aggregates: seeds, or 1), `n_diverged` (runs
/// that blew up), `diverged_at` (the earliest blow-up, nan if none), `window_diverged` (runs
/// whose blow-up cuts or precedes this window); per shown metric `<field>_median`, `_min`,
/// `_max` over the runs with a value and `_n`, how many have one (an error counts no run
/// that blew up before the window; `frac_*` metrics are in percent, named `<field>_percent_*`).
std::vector<std::string> summary_csv_columns();
/// The cells of summary_csv_columns() for one row: `runs` holds one summary per seed (each
/// over its sequences), or the one run of an unseeded method.
std::vector<TableCell> summary_csv_cells(const std::vector<RolloutSummary>& runs, SummaryScope window);

/// How summary_table_cells_over_seeds combines n seeds, for captions.
std::string seed_statistics_text(size_t n);

/// The window's frame range as text, e.g. "test (frames ≥ 750)".
std::string window_label(const RolloutSummary& s, SummaryScope window);

/// One line (no newline) of the CLI printout: header, and one window of one rollout.
std::string format_summary_header();
std::string format_summary_row(const std::string& method, const std::string& sequence, const RolloutSummary& s,
                               SummaryScope window);

} // namespace lb
