#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <set>

#include "core/error.hpp"
#include "eval/rollout.hpp"
#include "eval/summary_schema.hpp"
#include "io/hdf5.hpp"
#include "io/table.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

/// A summary whose every metric has a distinct value with a full 53-bit mantissa.
RolloutSummary distinct_summary(double offset = 0.0)
{
    RolloutSummary s;
    int k = 0;
    for (const SummaryMetric& m : summary_metrics()) {
        ++k;
        m.set(s, m.integer ? double(100 * k) + offset : std::sqrt(2.0 + k + offset) * std::pow(10.0, k % 7 - 4));
    }
    return s;
}

// ---- references: what the five hand-written places did before the schema ------------

TableCell legacy_number(double v, int digits = 3)
{
    return std::isfinite(v) ? TableCell::significant(v, digits) : TableCell::missing("nan");
}

const std::vector<std::string> kLegacyColumns{"stable / frames", "final RMSE", "mean RMSE", "max BC viol. (m)",
                                              "KE ratio",        "residual",   "STED",      "integrate (ms)",
                                              "decode (ms)",     "total (ms)"};

std::vector<TableCell> legacy_cells(const RolloutSummary& s)
{
    return {TableCell(std::to_string(s.stable_horizon) + " / " + std::to_string(s.frames), double(s.stable_horizon)),
            legacy_number(s.final_rmse),
            legacy_number(s.mean_rmse),
            legacy_number(s.max_bc_violation),
            legacy_number(s.ke_ratio),
            legacy_number(s.mean_residual),
            legacy_number(s.sted),
            legacy_number(s.integrate_ms),
            legacy_number(s.decode_ms),
            legacy_number(s.total_ms)};
}

RolloutSummary legacy_mean_summary(const std::vector<RolloutSummary>& all)
{
    RolloutSummary m;
    if (all.empty()) return m;
    m.stable_horizon = all.front().stable_horizon;
    m.frames = all.front().frames;
    for (const auto& s : all) {
        m.stable_horizon = std::min(m.stable_horizon, s.stable_horizon);
        m.frames = std::min(m.frames, s.frames);
        m.final_rmse += s.final_rmse / double(all.size());
        m.mean_rmse += s.mean_rmse / double(all.size());
        m.max_bc_violation = std::max(m.max_bc_violation, s.max_bc_violation);
        m.ke_ratio += s.ke_ratio / double(all.size());
        m.mean_residual += s.mean_residual / double(all.size());
        m.m_rms += s.m_rms / double(all.size());
        m.sted += s.sted / double(all.size());
        m.integrate_ms += s.integrate_ms / double(all.size());
        m.decode_ms += s.decode_ms / double(all.size());
        m.total_ms += s.total_ms / double(all.size());
    }
    return m;
}

std::string legacy_header()
{
    char b[512];
    std::snprintf(b, sizeof(b), "%-18s %-22s %6s %8s %10s %10s %10s %8s %10s %9s %9s", "method", "sequence", "frames",
                  "stable", "final_rmse", "mean_rmse", "max_bc_m", "ke_ratio", "residual", "sted", "total_ms");
    return b;
}

std::string legacy_row(const std::string& method, const std::string& sequence, const RolloutSummary& s)
{
    char b[512];
    std::snprintf(b, sizeof(b), "%-18s %-22s %6d %8d %10.4g %10.4g %10.4g %8.3f %10.4g %9.4g %9.4f", method.c_str(),
                  sequence.c_str(), s.frames, s.stable_horizon, s.final_rmse, s.mean_rmse, s.max_bc_violation,
                  s.ke_ratio, s.mean_residual, s.sted, s.total_ms);
    return b;
}

/// Summaries that exercise the formatting: typical, tiny/huge, non-finite, zero.
std::vector<RolloutSummary> formatting_cases()
{
    RolloutSummary typical;
    typical.frames = 400;
    typical.stable_horizon = 103;
    typical.final_rmse = 0.0123456;
    typical.mean_rmse = 0.00098765;
    typical.max_bc_violation = 1.5e-7;
    typical.ke_ratio = 0.87654;
    typical.mean_residual = 12345.678;
    typical.m_rms = 0.02;
    typical.sted = 0.333333;
    typical.integrate_ms = 0.0421;
    typical.decode_ms = 0.3;
    typical.total_ms = 0.3421;
    RolloutSummary diverged = typical;
    diverged.final_rmse = kNan;
    diverged.mean_rmse = kInf;
    diverged.max_bc_violation = -kInf;
    diverged.ke_ratio = 0.0;
    diverged.sted = kNan;
    return {typical, diverged, RolloutSummary{}, distinct_summary()};
}

// ---- the schema itself ------------------------------------------------------------------

TEST(SummarySchema, NamesAndTitlesAreUnique)
{
    std::set<std::string> names, titles;
    for (const SummaryMetric& m : summary_metrics()) {
        EXPECT_TRUE(names.insert(m.name).second) << "duplicate name " << m.name;
        EXPECT_TRUE(titles.insert(m.title).second) << "duplicate title " << m.title;
        EXPECT_GT(std::strlen(m.name), 0u);
        if (m.cli.header) {
            EXPECT_GT(m.cli.width, 0) << m.name;
        }
    }
    EXPECT_EQ(names.size(), summary_metrics().size());
}

TEST(SummarySchema, AccessorsReachTheirOwnField)
{
    // Setting one metric changes that metric only (a copy-paste slip in the list would not).
    for (const SummaryMetric& m : summary_metrics()) {
        RolloutSummary s;
        m.set(s, 7.0);
        for (const SummaryMetric& other : summary_metrics()) {
            EXPECT_EQ(other.get(s), &other == &m ? 7.0 : 0.0) << "setting " << m.name << ", reading " << other.name;
        }
    }
}

TEST(SummarySchema, KnownMetricsHaveTheirAttributeNamesAndUnits)
{
    // The HDF5 attribute names of rollout files written before the schema.
    const std::vector<std::string> legacy{"frames",  "stable_horizon", "final_rmse", "mean_rmse",
                                          "max_bc_violation", "ke_ratio", "mean_residual", "m_rms",
                                          "sted", "integrate_ms", "decode_ms", "total_ms"};
    std::set<std::string> names;
    for (const SummaryMetric& m : summary_metrics()) names.insert(m.name);
    for (const auto& n : legacy) EXPECT_EQ(names.count(n), 1u) << n;
    for (const SummaryMetric& m : summary_metrics()) {
        const std::string name = m.name;
        if (name == "max_bc_violation" || name == "m_rms") {
            EXPECT_STREQ(m.unit, "m");
        }
        if (name == "total_ms") {
            EXPECT_STREQ(m.unit, "ms");
        }
    }
}

// ---- tables and printout render as before ----------------------------------------------

TEST(SummarySchema, TableColumnsAndCellsMatchTheLegacyTable)
{
    EXPECT_EQ(summary_table_columns(), kLegacyColumns);
    Table now, before;
    now.title = before.title = "t";
    now.columns = before.columns = {"method"};
    for (const auto& c : summary_table_columns()) now.columns.push_back(c);
    for (const auto& c : kLegacyColumns) before.columns.push_back(c);
    for (const RolloutSummary& s : formatting_cases()) {
        const std::vector<TableCell> cells = summary_table_cells(s);
        const std::vector<TableCell> expected = legacy_cells(s);
        ASSERT_EQ(cells.size(), expected.size());
        for (size_t c = 0; c < cells.size(); ++c) {
            EXPECT_EQ(cells[c].text, expected[c].text) << kLegacyColumns[c];
            ASSERT_EQ(cells[c].value.has_value(), expected[c].value.has_value()) << kLegacyColumns[c];
            if (cells[c].value) {
                EXPECT_TRUE(same_bits(*cells[c].value, *expected[c].value)) << kLegacyColumns[c];
            }
        }
        std::vector<TableCell> row{"m"}, legacy_row_cells{"m"};
        row.insert(row.end(), cells.begin(), cells.end());
        legacy_row_cells.insert(legacy_row_cells.end(), expected.begin(), expected.end());
        now.add_row(row);
        before.add_row(legacy_row_cells);
    }
    EXPECT_EQ(to_markdown(now), to_markdown(before));
    EXPECT_EQ(to_csv(now), to_csv(before));
    EXPECT_EQ(to_latex(now), to_latex(before));
}

TEST(SummarySchema, TableCellsOfKnownValues)
{
    const RolloutSummary s = formatting_cases()[0];
    const std::vector<TableCell> cells = summary_table_cells(s);
    ASSERT_EQ(cells.size(), 10u);
    EXPECT_EQ(cells[0].text, "103 / 400");
    EXPECT_EQ(*cells[0].value, 103.0);
    EXPECT_EQ(cells[1].text, "0.0123");
    EXPECT_EQ(cells[3].text, "1.5e-07");
    EXPECT_EQ(cells[5].text, "1.23e+04");
    EXPECT_EQ(cells[9].text, "0.342");
    const std::vector<TableCell> diverged = summary_table_cells(formatting_cases()[1]);
    EXPECT_EQ(diverged[1].text, "nan");
    EXPECT_TRUE(std::isnan(*diverged[1].value));
    EXPECT_EQ(diverged[2].text, "nan");  // +inf, as before
    EXPECT_EQ(diverged[4].text, "0");
}

TEST(SummarySchema, CliPrintoutMatchesTheLegacyPrintf)
{
    EXPECT_EQ(format_summary_header(), legacy_header());
    for (const RolloutSummary& s : formatting_cases()) {
        EXPECT_EQ(format_summary_row("self_supervised", "corners_line", s), legacy_row("self_supervised", "corners_line", s));
    }
    // Names longer than their column are not cut.
    const std::string long_name(40, 'x');
    EXPECT_EQ(format_summary_row(long_name, long_name, formatting_cases()[0]),
              legacy_row(long_name, long_name, formatting_cases()[0]));
}

// ---- aggregation --------------------------------------------------------------------------

TEST(SummarySchema, AggregateFollowsEachMetricsRule)
{
    RolloutSummary a = formatting_cases()[0], b = distinct_summary();
    b.stable_horizon = 50;
    b.frames = 300;
    const RolloutSummary m = aggregate({a, b});
    EXPECT_EQ(m.stable_horizon, 50);
    EXPECT_EQ(m.frames, 300);
    EXPECT_EQ(m.max_bc_violation, std::max(a.max_bc_violation, b.max_bc_violation));
    EXPECT_EQ(m.final_rmse, a.final_rmse / 2.0 + b.final_rmse / 2.0);
    EXPECT_EQ(m.total_ms, a.total_ms / 2.0 + b.total_ms / 2.0);
    for (const SummaryMetric& metric : summary_metrics()) {
        const double va = metric.get(a), vb = metric.get(b), v = metric.get(m);
        switch (metric.aggregation) {
        case SummaryAggregation::Mean: EXPECT_EQ(v, va / 2.0 + vb / 2.0) << metric.name; break;
        case SummaryAggregation::Max: EXPECT_EQ(v, std::max(va, vb)) << metric.name; break;
        case SummaryAggregation::Min: EXPECT_EQ(v, std::min(va, vb)) << metric.name; break;
        }
    }
    const RolloutSummary empty = aggregate({});
    for (const SummaryMetric& metric : summary_metrics()) EXPECT_EQ(metric.get(empty), 0.0) << metric.name;
}

TEST(SummarySchema, AggregateIsBitIdenticalToTheLegacyMeanSummary)
{
    std::vector<RolloutSummary> all;
    for (int k = 0; k < 7; ++k) all.push_back(distinct_summary(0.37 * k));
    all[3].max_bc_violation = kNan;  // skipped by the max, as before
    for (size_t n = 1; n <= all.size(); ++n) {
        const std::vector<RolloutSummary> some(all.begin(), all.begin() + long(n));
        const RolloutSummary now = aggregate(some), before = legacy_mean_summary(some);
        for (const SummaryMetric& m : summary_metrics()) {
            EXPECT_TRUE(same_bits(m.get(now), m.get(before))) << m.name << " over " << n << ": " << m.get(now)
                                                              << " vs " << m.get(before);
        }
    }
}

// ---- HDF5 ------------------------------------------------------------------------------

TEST(SummarySchema, EveryMetricRoundTripsThroughHdf5BitExactly)
{
    const std::string path = testing::fresh_dir("summary_schema") + "/summary.h5";
    const RolloutSummary s = distinct_summary();
    RolloutSummary odd = formatting_cases()[1];  // NaN and ±inf survive too
    odd.integrate_ms = std::nextafter(1.0, 2.0);
    {
        h5::File f = h5::File::create(path);
        write_summary(f, "a", s);
        write_summary(f, "b/c", odd);
    }
    const h5::File f = h5::File::open(path);
    for (const auto& [group, expected] : {std::pair{"a", s}, std::pair{"b/c", odd}}) {
        const RolloutSummary back = read_summary(f, group);
        for (const SummaryMetric& m : summary_metrics()) {
            ASSERT_TRUE(f.has_attribute(group, m.name)) << m.name;
            EXPECT_TRUE(same_bits(m.get(back), m.get(expected))) << group << " " << m.name;
        }
    }
}

TEST(SummarySchema, ReadsTheAttributeLayoutWrittenBeforeTheSchema)
{
    const std::string path = testing::fresh_dir("summary_schema_legacy") + "/legacy.h5";
    const RolloutSummary s = distinct_summary();
    {
        // What save_rollouts wrote by hand before the schema.
        h5::File f = h5::File::create(path);
        const std::string g = "rollouts/0";
        f.set_attribute(g, "frames", (long long)s.frames);
        f.set_attribute(g, "stable_horizon", (long long)s.stable_horizon);
        f.set_attribute(g, "final_rmse", s.final_rmse);
        f.set_attribute(g, "mean_rmse", s.mean_rmse);
        f.set_attribute(g, "max_bc_violation", s.max_bc_violation);
        f.set_attribute(g, "ke_ratio", s.ke_ratio);
        f.set_attribute(g, "mean_residual", s.mean_residual);
        f.set_attribute(g, "m_rms", s.m_rms);
        f.set_attribute(g, "sted", s.sted);
        f.set_attribute(g, "integrate_ms", s.integrate_ms);
        f.set_attribute(g, "decode_ms", s.decode_ms);
        f.set_attribute(g, "total_ms", s.total_ms);
        // A file from before a metric existed, and one missing an integer metric.
        f.set_attribute("old", "frames", 10LL);
        f.set_attribute("old", "stable_horizon", 8LL);
        f.set_attribute("broken", "final_rmse", 0.5);
    }
    const h5::File f = h5::File::open(path);
    const RolloutSummary back = read_summary(f, "rollouts/0");
    for (const SummaryMetric& m : summary_metrics()) EXPECT_TRUE(same_bits(m.get(back), m.get(s))) << m.name;
    const RolloutSummary old = read_summary(f, "old");
    EXPECT_EQ(old.frames, 10);
    EXPECT_EQ(old.stable_horizon, 8);
    EXPECT_TRUE(std::isnan(old.sted));
    EXPECT_THROW(read_summary(f, "broken"), IoError);
}

TEST(SummarySchema, SaveAndLoadRolloutsRoundTripTheSummary)
{
    const std::string path = testing::fresh_dir("summary_schema_rollouts") + "/rollouts.h5";
    std::vector<RolloutResult> results(2);
    for (size_t k = 0; k < results.size(); ++k) {
        results[k].method = "m" + std::to_string(k);
        results[k].sequence = "s" + std::to_string(k);
        results[k].metrics = MatrixXd::Constant(3, kNumMetricColumns, 0.25 * double(k));
        results[k].summary = distinct_summary(double(k));
    }
    results[1].summary.final_rmse = kNan;
    save_rollouts(results, path, "config");
    const std::vector<RolloutRecord> records = load_rollout_summaries(path);
    ASSERT_EQ(records.size(), results.size());
    for (size_t k = 0; k < results.size(); ++k) {
        EXPECT_EQ(records[k].method, results[k].method);
        EXPECT_EQ(records[k].sequence, results[k].sequence);
        for (const SummaryMetric& m : summary_metrics()) {
            EXPECT_TRUE(same_bits(m.get(records[k].summary), m.get(results[k].summary))) << k << " " << m.name;
        }
    }
}

// ---- per-frame columns ------------------------------------------------------------------

TEST(MetricColumns, OneEntryPerColumnWithUniqueNames)
{
    ASSERT_EQ(metric_columns().size(), size_t(kNumMetricColumns));
    ASSERT_EQ(metric_column_names().size(), size_t(kNumMetricColumns));
    EXPECT_EQ(metric_column_names()[kRmse], "rmse");
    EXPECT_EQ(metric_column_names()[kDecodeSeconds], "decode_seconds");
    EXPECT_STREQ(metric_columns()[kBcViolation].unit, "m");
    EXPECT_STREQ(metric_columns()[kIntegrateSeconds].unit, "s");
    const std::set<std::string> unique(metric_column_names().begin(), metric_column_names().end());
    EXPECT_EQ(unique.size(), metric_column_names().size());
}

} // namespace
} // namespace lb
