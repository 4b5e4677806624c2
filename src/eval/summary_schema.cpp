#include "eval/summary_schema.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <type_traits>

#include "core/error.hpp"
#include "io/hdf5.hpp"

namespace lb {
namespace {

// Vocabulary of the LB_SUMMARY_METRICS columns.
constexpr SummaryAggregation kMean = SummaryAggregation::Mean;
constexpr SummaryAggregation kMax = SummaryAggregation::Max;
constexpr SummaryAggregation kMin = SummaryAggregation::Min;
constexpr SummaryAggregation kSum = SummaryAggregation::Sum;

constexpr SummaryMetric::Table sig(int digits) { return {true, digits, nullptr, false}; }
constexpr SummaryMetric::Table error(int digits) { return {true, digits, nullptr, true}; }
constexpr SummaryMetric::Table cell(SummaryCellFn fn) { return {true, 0, fn, false}; }
constexpr SummaryMetric::Table hidden() { return {false, 0, nullptr, false}; }
constexpr SummaryMetric::Cli cli(const char* header, int width, const char* format) { return {header, width, format}; }
constexpr SummaryMetric::Cli no_cli() { return {nullptr, 0, ""}; }

const SummaryWindow& window_of(const RolloutSummary& s, SummaryScope scope)
{
    return scope == SummaryScope::Train ? s.train : s.test;
}

/// The stable (blow-up) horizon: "T / T" if never, "diverged @h" otherwise; sorts by h.
TableCell stable_cell(const RolloutSummary& s, const SummaryMetric&)
{
    const std::string text = s.stable_horizon < s.frames ? "diverged @" + std::to_string(s.stable_horizon)
                                                         : std::to_string(s.stable_horizon) + " / " + std::to_string(s.frames);
    return TableCell(text, double(s.stable_horizon));
}

/// A looser tier's horizon: "@h", or "never" (sorts as the frame count).
TableCell tier_cell(const RolloutSummary& s, const SummaryMetric& m)
{
    const int h = int(m.get(s));
    return TableCell(h < s.frames ? "@" + std::to_string(h) : "never", double(h));
}

/// Frames the errors of a window were aggregated over: "a of w".
TableCell evaluated_cell(const RolloutSummary& s, const SummaryMetric& m)
{
    const SummaryWindow& w = window_of(s, m.scope);
    if (w.window_frames == 0) return TableCell::missing("— (empty)");
    return TableCell(std::to_string(w.evaluated_frames) + " of " + std::to_string(w.window_frames),
                     double(w.evaluated_frames));
}

/// A fraction as a percentage with one decimal.
TableCell percent_cell(const RolloutSummary& s, const SummaryMetric& m)
{
    if (window_of(s, m.scope).window_frames == 0) return TableCell::missing("— (empty)");
    const double v = m.get(s);
    return std::isfinite(v) ? TableCell::fixed(100.0 * v, 1) : TableCell::missing("nan");
}

TableCell significant_cell(double v, int digits)
{
    return std::isfinite(v) ? TableCell::significant(v, digits) : TableCell::missing("nan");
}

/// An error of a window, aggregated before the stable horizon: never a bare number
/// when the rollout blew up before the end of the window.
TableCell error_cell(const RolloutSummary& s, const SummaryMetric& m)
{
    const SummaryWindow& w = window_of(s, m.scope);
    if (w.window_frames == 0) return TableCell::missing("— (empty)");
    const std::string diverged = "diverged @" + std::to_string(s.stable_horizon);
    const double v = m.get(s);
    if (w.evaluated_frames == 0) return TableCell::missing(diverged);
    TableCell c = significant_cell(v, m.table.digits);
    if (!std::isfinite(v)) c = TableCell::missing("n/a");  // e.g. a KE ratio without ground-truth motion
    if (w.evaluated_frames < w.window_frames) c.text += " (" + diverged + ")";
    return c;
}

#define LB_SCHEMA_ENTRY(scope_id, prefix, member, type, field, title, unit, agg, table, cli)                              \
    metrics.push_back(SummaryMetric{prefix #field, #field, scope_id, title, unit, agg, std::is_integral_v<type>, table, \
                                    cli, [](const RolloutSummary& s) { return double(s member field); },              \
                                    [](RolloutSummary& s, double v) { s member field = static_cast<type>(v); }});
#define LB_SCHEMA_rollout(type, field, title, unit, agg, table, cli) \
    LB_SCHEMA_ENTRY(SummaryScope::Rollout, "", ., type, field, title, unit, agg, table, cli)
#define LB_SCHEMA_window(type, field, title, unit, agg, table, cli)                                      \
    LB_SCHEMA_ENTRY(SummaryScope::Train, "train_", .train., type, field, title, unit, agg, table, cli) \
    LB_SCHEMA_ENTRY(SummaryScope::Test, "test_", .test., type, field, title, unit, agg, table, cli)
#define LB_SCHEMA_LINE(scope, ...) LB_SCHEMA_##scope(__VA_ARGS__)

std::vector<SummaryMetric> make_summary_metrics()
{
    std::vector<SummaryMetric> metrics;
    LB_SUMMARY_METRICS(LB_SCHEMA_LINE)
    return metrics;
}

#undef LB_SCHEMA_LINE
#undef LB_SCHEMA_window
#undef LB_SCHEMA_rollout
#undef LB_SCHEMA_ENTRY

/// snprintf into a std::string of the right length (no truncation of long names).
template <class... Args>
std::string printf_string(const char* format, Args... args)
{
    const int n = std::snprintf(nullptr, 0, format, args...);
    std::string out(size_t(std::max(n, 0)), '\0');
    std::snprintf(out.data(), out.size() + 1, format, args...);
    return out;
}

std::string cli_value(const SummaryMetric& m, const RolloutSummary& s)
{
    return m.integer ? printf_string(m.cli.format, m.cli.width, int(m.get(s)))
                     : printf_string(m.cli.format, m.cli.width, m.get(s));
}

} // namespace

const std::vector<SummaryMetric>& summary_metrics()
{
    static const std::vector<SummaryMetric> metrics = make_summary_metrics();
    return metrics;
}

const char* to_string(SummaryScope scope)
{
    switch (scope) {
    case SummaryScope::Rollout: return "rollout";
    case SummaryScope::Train: return "train";
    case SummaryScope::Test: return "test";
    }
    return "?";
}

RolloutSummary aggregate(const std::vector<RolloutSummary>& all)
{
    RolloutSummary out;
    if (all.empty()) return out;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    for (const SummaryMetric& m : summary_metrics()) {
        double acc = 0.0;
        int finite = 0;
        for (const RolloutSummary& s : all) {
            const double v = m.get(s);
            switch (m.aggregation) {
            case SummaryAggregation::Mean:
            case SummaryAggregation::Max:
                if (!std::isfinite(v)) break;
                acc = finite == 0 ? v : m.aggregation == SummaryAggregation::Max ? std::max(acc, v) : acc + v;
                ++finite;
                break;
            case SummaryAggregation::Min: acc = &s == &all.front() ? v : std::min(acc, v); break;
            case SummaryAggregation::Sum: acc += v; break;
            }
        }
        if (m.aggregation == SummaryAggregation::Mean) acc = finite > 0 ? acc / double(finite) : nan;
        if (m.aggregation == SummaryAggregation::Max && finite == 0) acc = nan;
        m.set(out, acc);
    }
    return out;
}

void write_summary(h5::File& file, const std::string& group, const RolloutSummary& s)
{
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.integer) {
            file.set_attribute(group, m.name, static_cast<long long>(m.get(s)));
        } else {
            file.set_attribute(group, m.name, m.get(s));
        }
    }
}

RolloutSummary read_summary(const h5::File& file, const std::string& group)
{
    RolloutSummary s;
    // The integer counters are always written. A summary with none of them predates the
    // training/test windows; one with some but not all is damaged (a truncated or edited file).
    int integers = 0, present = 0;
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.integer) continue;
        ++integers;
        present += file.has_attribute(group, m.name) ? 1 : 0;
    }
    for (const SummaryMetric& m : summary_metrics()) {
        if (!file.has_attribute(group, m.name)) {
            if (m.integer && present == 0)
                throw IoError("rollout file '" + file.path() + "': summary '" + group + "' has none of its " +
                              std::to_string(integers) + " counters (attribute '" + m.name +
                              "' first): written by a latentbench older than the training/test windows; roll out again");
            if (m.integer)
                throw IoError("rollout file '" + file.path() + "': summary '" + group + "' lacks attribute '" + m.name +
                              "' (it has " + std::to_string(present) + " of its " + std::to_string(integers) +
                              " counters): the file is damaged; roll out again");
            m.set(s, std::numeric_limits<double>::quiet_NaN());
        } else if (m.integer) {
            m.set(s, double(file.attribute_int(group, m.name)));
        } else {
            m.set(s, file.attribute_double(group, m.name));
        }
    }
    return s;
}

std::vector<std::string> summary_table_columns()
{
    std::vector<std::string> columns;
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.table.shown && m.scope != SummaryScope::Test) columns.emplace_back(m.title);
    }
    return columns;
}

std::vector<TableCell> summary_table_cells(const RolloutSummary& s, SummaryScope window)
{
    std::vector<TableCell> cells;
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.table.shown || (m.scope != SummaryScope::Rollout && m.scope != window)) continue;
        cells.push_back(m.table.cell    ? m.table.cell(s, m)
                        : m.table.error ? error_cell(s, m)
                                        : significant_cell(m.get(s), m.table.digits));
    }
    return cells;
}

namespace {

/// 97.5 % quantile of Student's t with `df` degrees of freedom (two-sided 95 %).
double student_t_975(size_t df)
{
    static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                                   2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                                   2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
    if (df == 0) return std::numeric_limits<double>::quiet_NaN();
    return df <= 30 ? table[df - 1] : 1.96;
}

std::string format_significant(double v, int digits) { return TableCell::significant(v, digits).text; }

/// "mean ± h" (n ≥ 5) or "median [min, max]" (n < 5) of finite values; the cell's value
/// is the mean or the median.
TableCell statistics_cell(std::vector<double> values, int digits)
{
    if (values.empty()) return TableCell::missing("nan");
    std::sort(values.begin(), values.end());
    // Counts (every value an integer: horizons, frames) keep all their integer digits, so a
    // 1,500-frame horizon reads 1500, not 1.5e+03.
    if (std::all_of(values.begin(), values.end(), [](double v) { return v == std::floor(v); })) {
        const double largest = std::max(std::abs(values.front()), std::abs(values.back()));
        if (largest >= 1.0 && largest < 1e15) digits = std::max(digits, int(std::floor(std::log10(largest))) + 1);
    }
    const size_t n = values.size();
    if (n == 1) return TableCell(format_significant(values[0], digits), values[0]);
    if (n < 5) {
        const double median = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
        return TableCell(format_significant(median, digits) + " [" + format_significant(values.front(), digits) + ", " +
                             format_significant(values.back(), digits) + "]",
                         median);
    }
    double mean = 0.0;
    for (double v : values) mean += v / double(n);
    double var = 0.0;
    for (double v : values) var += (v - mean) * (v - mean) / double(n - 1);
    double half = student_t_975(n - 1) * std::sqrt(var / double(n));
    if (half < 1e-12 * std::abs(mean)) half = 0.0;  // rounding of equal values, not a spread
    return TableCell(format_significant(mean, digits) + " ± " + format_significant(half, digits), mean);
}

} // namespace

std::string seed_statistics_text(size_t n)
{
    if (n >= 5) return "mean ± half-width of the 95 % Student-t interval over the " + std::to_string(n) + " seeds";
    if (n >= 2) return "median [min, max] over the " + std::to_string(n) + " seeds (fewer than 5: no interval)";
    return "one seed";
}

std::vector<TableCell> summary_table_cells_over_seeds(const std::vector<RolloutSummary>& per_seed, SummaryScope window)
{
    if (per_seed.size() == 1) return summary_table_cells(per_seed.front(), window);
    std::vector<TableCell> cells;
    const size_t n = per_seed.size();
    int earliest = std::numeric_limits<int>::max();
    for (const RolloutSummary& s : per_seed) earliest = std::min(earliest, s.stable_horizon);
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.table.shown || (m.scope != SummaryScope::Rollout && m.scope != window)) continue;
        std::vector<double> values;
        size_t cut = 0, none = 0, empty = 0, diverged = 0;
        int earliest_cut = std::numeric_limits<int>::max();
        for (const RolloutSummary& s : per_seed) {
            const SummaryWindow& w = window_of(s, window);
            if (s.stable_horizon < s.frames) ++diverged;
            if (m.scope != SummaryScope::Rollout && w.window_frames == 0) {
                ++empty;
                continue;
            }
            if (m.scope != SummaryScope::Rollout && w.evaluated_frames < w.window_frames) {
                ++cut;
                earliest_cut = std::min(earliest_cut, s.stable_horizon);
            }
            if (m.table.error && w.evaluated_frames == 0) {
                ++none;
                continue;
            }
            const double v = m.get(s);
            if (std::isfinite(v)) values.push_back(m.table.cell == percent_cell ? 100.0 * v : v);
        }
        if (empty == n) {
            cells.push_back(TableCell::missing("— (empty)"));
            continue;
        }
        if (m.table.error && none == n - empty) {
            cells.push_back(TableCell::missing("diverged @" + std::to_string(earliest_cut) + " (all " +
                                               std::to_string(none) + " seeds)"));
            continue;
        }
        const int digits = m.table.cell ? 3 : m.table.digits;
        TableCell c = statistics_cell(values, digits);
        // An aggregate over fewer runs than the row holds says how many it holds.
        const std::string held = values.size() < n - empty
                                     ? std::to_string(values.size()) + " of " + std::to_string(n - empty) + " seeds"
                                     : "";
        if (m.table.error && cut > 0)
            c.text += " (" + (held.empty() ? "" : held + "; ") + std::to_string(cut) + "/" + std::to_string(n - empty) +
                      " diverged, earliest @" + std::to_string(earliest_cut) + ")";
        else if (!held.empty())
            c.text += " (" + held + ")";
        if (m.table.cell == stable_cell && diverged > 0)
            c.text += " (" + std::to_string(diverged) + "/" + std::to_string(n) + " diverged, earliest @" +
                      std::to_string(earliest) + ")";
        cells.push_back(std::move(c));
    }
    return cells;
}

std::vector<std::string> summary_csv_columns()
{
    std::vector<std::string> columns{"n_seeds", "n_diverged", "diverged_at", "window_diverged"};
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.table.shown || m.scope == SummaryScope::Test) continue;
        const std::string base = std::string(m.field) + (m.table.cell == percent_cell ? "_percent" : "");
        for (const char* stat : {"_median", "_min", "_max", "_n"}) columns.push_back(base + stat);
    }
    return columns;
}

std::vector<TableCell> summary_csv_cells(const std::vector<RolloutSummary>& runs, SummaryScope window)
{
    const auto count = [](size_t k) { return TableCell(std::to_string(k), double(k)); };
    const auto value = [](double v) {
        return std::isfinite(v) ? TableCell(TableCell::significant(v, 6).text, v) : TableCell::missing("nan");
    };
    size_t diverged = 0, window_diverged = 0;
    int earliest = std::numeric_limits<int>::max();
    for (const RolloutSummary& s : runs) {
        if (s.stable_horizon >= s.frames) continue;
        ++diverged;
        earliest = std::min(earliest, s.stable_horizon);
        const SummaryWindow& w = window_of(s, window);
        if (w.window_frames > 0 && w.evaluated_frames < w.window_frames) ++window_diverged;
    }
    std::vector<TableCell> cells{count(runs.size()), count(diverged),
                                 diverged > 0 ? value(double(earliest)) : TableCell::missing("nan"), count(window_diverged)};
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.table.shown || (m.scope != SummaryScope::Rollout && m.scope != window)) continue;
        // The values the Markdown cell aggregates: an empty window has none, an error none
        // from a run that blew up before the window began.
        std::vector<double> values;
        for (const RolloutSummary& s : runs) {
            const SummaryWindow& w = window_of(s, window);
            if (m.scope != SummaryScope::Rollout && w.window_frames == 0) continue;
            if (m.table.error && w.evaluated_frames == 0) continue;
            const double v = m.get(s);
            if (std::isfinite(v)) values.push_back(m.table.cell == percent_cell ? 100.0 * v : v);
        }
        std::sort(values.begin(), values.end());
        const size_t n = values.size();
        const double nan = std::numeric_limits<double>::quiet_NaN();
        const double median = n == 0 ? nan : n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
        cells.push_back(value(median));
        cells.push_back(value(n ? values.front() : nan));
        cells.push_back(value(n ? values.back() : nan));
        cells.push_back(count(n));
    }
    return cells;
}

std::string window_label(const RolloutSummary& s, SummaryScope window)
{
    const int split = std::max(s.train_frames, 2);
    if (window == SummaryScope::Test) return "test (frames >= " + std::to_string(split) + ")";
    return split > 2 ? "train (frames 2-" + std::to_string(split - 1) + ")" : "train (none)";
}

std::string format_summary_header()
{
    std::string line = printf_string("%-18s %-22s %-6s", "method", "sequence", "window");
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.cli.header && m.scope != SummaryScope::Test) line += printf_string(" %*s", m.cli.width, m.cli.header);
    }
    return line;
}

std::string format_summary_row(const std::string& method, const std::string& sequence, const RolloutSummary& s,
                               SummaryScope window)
{
    std::string line = printf_string("%-18s %-22s %-6s", method.c_str(), sequence.c_str(), to_string(window));
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.cli.header && (m.scope == SummaryScope::Rollout || m.scope == window)) line += " " + cli_value(m, s);
    }
    return line;
}

} // namespace lb
