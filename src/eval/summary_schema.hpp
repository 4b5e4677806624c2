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
//   type    int or double (an int is written as a 64-bit integer attribute)
//   field   the RolloutSummary member; also its HDF5 attribute and CSV name
//   title   column title in the comparison tables
//   unit    SI-style unit, "" if dimensionless (relative metrics, ratios)
//   agg     over sequences: kMean, kMax or kMin
//   table   how the comparison table shows it:
//             sig(d)       d significant digits, non-finite as "nan"
//             cell(fn)     a custom cell, fn(const RolloutSummary&, const SummaryMetric&)
//             hidden()     not in the table
//   cli     cli(header, width, printf conversion taking (width, value)), or no_cli()
//
// Definitions of the metrics: eval/metrics.hpp. Times are medians per frame after
// warm-up; M_rms is in metres (unscaled), RMSEs are relative to the rest
// bounding-box diagonal.
#include <string>
#include <vector>

#include "io/table.hpp"

// clang-format off
#define LB_SUMMARY_METRICS(X)                                                                                          \
  /* type    field             title               unit      agg    table                cli                         */ \
    X(int,    frames,           "frames",           "frames", kMin,  hidden(),            cli("frames", 6, "%*d"))      \
    X(int,    stable_horizon,   "stable / frames",  "frames", kMin,  cell(horizon_cell),  cli("stable", 8, "%*d"))      \
    X(double, final_rmse,       "final RMSE",       "",       kMean, sig(3),              cli("final_rmse", 10, "%*.4g")) \
    X(double, mean_rmse,        "mean RMSE",        "",       kMean, sig(3),              cli("mean_rmse", 10, "%*.4g")) \
    X(double, max_bc_violation, "max BC viol. (m)", "m",      kMax,  sig(3),              cli("max_bc_m", 10, "%*.4g")) \
    X(double, ke_ratio,         "KE ratio",         "",       kMean, sig(3),              cli("ke_ratio", 8, "%*.3f"))  \
    X(double, mean_residual,    "residual",         "",       kMean, sig(3),              cli("residual", 10, "%*.4g")) \
    X(double, m_rms,            "M_rms (m)",        "m",      kMean, hidden(),            no_cli())                     \
    X(double, sted,             "STED",             "",       kMean, sig(3),              cli("sted", 9, "%*.4g"))      \
    X(double, integrate_ms,     "integrate (ms)",   "ms",     kMean, sig(3),              no_cli())                     \
    X(double, decode_ms,        "decode (ms)",      "ms",     kMean, sig(3),              no_cli())                     \
    X(double, total_ms,         "total (ms)",       "ms",     kMean, sig(3),              cli("total_ms", 9, "%*.4f"))
// clang-format on

namespace lb {

namespace h5 {
class File;
}

struct RolloutSummary {
#define LB_SUMMARY_FIELD(type, field, ...) type field = 0;
    LB_SUMMARY_METRICS(LB_SUMMARY_FIELD)
#undef LB_SUMMARY_FIELD
};

/// How a metric combines over the sequences of a method (one table row).
enum class SummaryAggregation {
    Mean,  ///< arithmetic mean
    Max,   ///< worst case, starting from 0 (a NaN is skipped, as before the schema)
    Min    ///< worst case of a "higher is better" count, e.g. the stable horizon
};

struct SummaryMetric;
/// Table cell of one metric of a summary (the per-metric formatting hook).
using SummaryCellFn = TableCell (*)(const RolloutSummary& s, const SummaryMetric& metric);

struct SummaryMetric {
    const char* name;   ///< RolloutSummary field, HDF5 attribute and CSV name
    const char* title;  ///< comparison-table column title
    const char* unit;   ///< "" if dimensionless
    SummaryAggregation aggregation;
    bool integer;  ///< int field (64-bit integer attribute)
    struct Table {
        bool shown = false;
        int digits = 3;               ///< significant digits of the default cell
        SummaryCellFn cell = nullptr; ///< nullptr: `digits` significant digits, non-finite as "nan"
    } table;
    struct Cli {
        const char* header = nullptr;  ///< nullptr: not printed
        int width = 0;
        const char* format = "";  ///< printf conversion taking (int width, value): "%*d" (int) or e.g. "%*.4g"
    } cli;
    double (*get)(const RolloutSummary&);
    void (*set)(RolloutSummary&, double);  ///< an int field takes the value truncated
};

/// Every summary metric, in the order of LB_SUMMARY_METRICS.
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

/// Titles of the metrics the comparison tables show, and their cells for one summary.
std::vector<std::string> summary_table_columns();
std::vector<TableCell> summary_table_cells(const RolloutSummary& s);

/// One line (no newline) of the CLI printout: header, and one rollout.
std::string format_summary_header();
std::string format_summary_row(const std::string& method, const std::string& sequence, const RolloutSummary& s);

} // namespace lb
