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

constexpr SummaryMetric::Table sig(int digits) { return {true, digits, nullptr}; }
constexpr SummaryMetric::Table cell(SummaryCellFn fn) { return {true, 0, fn}; }
constexpr SummaryMetric::Table hidden() { return {false, 0, nullptr}; }
constexpr SummaryMetric::Cli cli(const char* header, int width, const char* format) { return {header, width, format}; }
constexpr SummaryMetric::Cli no_cli() { return {nullptr, 0, ""}; }

/// "stable / frames" as text, the horizon as the sort value.
TableCell horizon_cell(const RolloutSummary& s, const SummaryMetric&)
{
    return TableCell(std::to_string(s.stable_horizon) + " / " + std::to_string(s.frames), double(s.stable_horizon));
}

TableCell significant_cell(double v, int digits)
{
    return std::isfinite(v) ? TableCell::significant(v, digits) : TableCell::missing("nan");
}

std::vector<SummaryMetric> make_summary_metrics()
{
    std::vector<SummaryMetric> metrics;
#define LB_SUMMARY_ENTRY(type, field, title, unit, agg, table, cli)                                             \
    metrics.push_back(SummaryMetric{#field, title, unit, agg, std::is_integral_v<type>, table, cli,              \
                                    [](const RolloutSummary& s) { return double(s.field); },                    \
                                    [](RolloutSummary& s, double v) { s.field = static_cast<type>(v); }});
    LB_SUMMARY_METRICS(LB_SUMMARY_ENTRY)
#undef LB_SUMMARY_ENTRY
    return metrics;
}

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

RolloutSummary aggregate(const std::vector<RolloutSummary>& all)
{
    RolloutSummary out;
    if (all.empty()) return out;
    const double n = double(all.size());
    for (const SummaryMetric& m : summary_metrics()) {
        double acc = m.aggregation == SummaryAggregation::Min ? m.get(all.front()) : 0.0;
        for (const RolloutSummary& s : all) {
            const double v = m.get(s);
            switch (m.aggregation) {
            case SummaryAggregation::Mean: acc += v / n; break;
            case SummaryAggregation::Max: acc = std::max(acc, v); break;
            case SummaryAggregation::Min: acc = std::min(acc, v); break;
            }
        }
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
    for (const SummaryMetric& m : summary_metrics()) {
        if (!file.has_attribute(group, m.name)) {
            if (m.integer) throw IoError("rollout summary '" + group + "' has no attribute '" + m.name + "'");
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
        if (m.table.shown) columns.emplace_back(m.title);
    }
    return columns;
}

std::vector<TableCell> summary_table_cells(const RolloutSummary& s)
{
    std::vector<TableCell> cells;
    for (const SummaryMetric& m : summary_metrics()) {
        if (!m.table.shown) continue;
        cells.push_back(m.table.cell ? m.table.cell(s, m) : significant_cell(m.get(s), m.table.digits));
    }
    return cells;
}

std::string format_summary_header()
{
    std::string line = printf_string("%-18s %-22s", "method", "sequence");
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.cli.header) line += printf_string(" %*s", m.cli.width, m.cli.header);
    }
    return line;
}

std::string format_summary_row(const std::string& method, const std::string& sequence, const RolloutSummary& s)
{
    std::string line = printf_string("%-18s %-22s", method.c_str(), sequence.c_str());
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.cli.header) line += " " + cli_value(m, s);
    }
    return line;
}

} // namespace lb
