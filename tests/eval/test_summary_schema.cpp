#include <gtest/gtest.h>

#include <algorithm>
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

/// Summaries that exercise the formatting: typical, diverged inside the test window, zero.
std::vector<RolloutSummary> formatting_cases()
{
    RolloutSummary typical;
    typical.frames = 400;
    typical.train_frames = 100;
    typical.sequences = 1;
    typical.stable_horizon = 400;
    typical.horizon_loose = 400;
    typical.horizon_tight = 103;
    for (SummaryWindow* w : {&typical.train, &typical.test}) {
        w->window_frames = w == &typical.train ? 98 : 300;
        w->evaluated_frames = w->window_frames;
        w->frac_tight = 0.25;
        w->final_rmse = 0.0123456;
        w->mean_rmse = 0.00098765;
        w->max_bc_violation = 1.5e-7;
        w->ke_ratio = 0.87654;
        w->mean_residual = 12345.678;
        w->m_rms = 0.02;
        w->sted = 0.333333;
    }
    typical.integrate_ms = 0.0421;
    typical.decode_ms = 0.3;
    typical.total_ms = 0.3421;
    RolloutSummary diverged = typical;
    diverged.stable_horizon = 214;
    diverged.test.evaluated_frames = 114;
    diverged.test.final_rmse = 0.4;
    return {typical, diverged, RolloutSummary{}, distinct_summary()};
}

// ---- the schema itself ------------------------------------------------------------------

TEST(SummarySchema, NamesAndTitlesAreUnique)
{
    std::set<std::string> names, titles;
    for (const SummaryMetric& m : summary_metrics()) {
        EXPECT_TRUE(names.insert(m.name).second) << "duplicate name " << m.name;
        if (m.scope != SummaryScope::Test) {  // the two windows share their titles (one row each)
            EXPECT_TRUE(titles.insert(m.title).second) << "duplicate title " << m.title;
        }
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

TEST(SummarySchema, WindowMetricsAppearOncePerWindow)
{
    std::set<std::string> names;
    for (const SummaryMetric& m : summary_metrics()) names.insert(m.name);
    for (const char* n : {"frames", "train_frames", "stable_horizon", "horizon_loose", "horizon_tight", "total_ms",
                          "train_mean_rmse", "test_mean_rmse", "train_ke_ratio", "test_ke_ratio",
                          "test_max_bc_violation", "test_frac_blowup", "test_evaluated_frames"}) {
        EXPECT_EQ(names.count(n), 1u) << n;
    }
    EXPECT_EQ(names.count("mean_rmse"), 0u) << "errors exist per window only";
    for (const SummaryMetric& m : summary_metrics()) {
        const std::string name = m.name;
        if (name.find("max_bc_violation") != std::string::npos || name.find("m_rms") != std::string::npos) {
            EXPECT_STREQ(m.unit, "m");
        }
        if (m.scope == SummaryScope::Train) {
            EXPECT_EQ(name, "train_" + std::string(m.field));
        }
        if (m.scope == SummaryScope::Test) {
            EXPECT_EQ(name, "test_" + std::string(m.field));
        }
    }
}

// ---- tables and printout ----------------------------------------------------------------

TEST(SummarySchema, TableCellsOfKnownValues)
{
    const std::vector<std::string> columns = summary_table_columns();
    const RolloutSummary s = formatting_cases()[0];
    const std::vector<TableCell> cells = summary_table_cells(s, SummaryScope::Test);
    ASSERT_EQ(cells.size(), columns.size());
    auto cell = [&](const std::vector<TableCell>& row, const std::string& title) {
        const auto it = std::find(columns.begin(), columns.end(), title);
        EXPECT_NE(it, columns.end()) << title;
        return row[size_t(it - columns.begin())];
    };
    EXPECT_EQ(cell(cells, "stable (blow-up)").text, "400 / 400");
    EXPECT_EQ(cell(cells, "first RMSE > 0.1").text, "never");
    EXPECT_EQ(cell(cells, "first RMSE > 0.02").text, "@103");
    EXPECT_EQ(cell(cells, "% frames > 0.02").text, "25.0");
    EXPECT_EQ(cell(cells, "frames aggregated").text, "300 of 300");
    EXPECT_EQ(cell(cells, "final RMSE").text, "0.0123");
    EXPECT_EQ(cell(cells, "max BC viol. (m)").text, "1.5e-07");
    EXPECT_EQ(cell(cells, "residual").text, "1.23e+04");
    EXPECT_EQ(cell(cells, "total (ms)").text, "0.342");
    const RolloutSummary d = formatting_cases()[1];
    const std::vector<TableCell> diverged = summary_table_cells(d, SummaryScope::Test);
    EXPECT_EQ(cell(diverged, "stable (blow-up)").text, "diverged @214");
    EXPECT_EQ(cell(diverged, "final RMSE").text, "0.4 (diverged @214)");
    EXPECT_EQ(cell(diverged, "KE ratio (free)").text, "0.877 (diverged @214)");
    EXPECT_EQ(cell(diverged, "frames aggregated").text, "114 of 300");
    // The training window ended before the blow-up: plain numbers.
    EXPECT_EQ(cell(summary_table_cells(d, SummaryScope::Train), "final RMSE").text, "0.0123");
}

TEST(SummarySchema, CliPrintsOneLinePerWindow)
{
    const std::string header = format_summary_header();
    EXPECT_NE(header.find("window"), std::string::npos);
    EXPECT_NE(header.find("stable"), std::string::npos);
    const RolloutSummary s = formatting_cases()[0];
    const std::string train = format_summary_row("self_supervised", "corners_line", s, SummaryScope::Train);
    const std::string test = format_summary_row("self_supervised", "corners_line", s, SummaryScope::Test);
    EXPECT_NE(train.find(" train "), std::string::npos) << train;
    EXPECT_NE(test.find(" test "), std::string::npos) << test;
    EXPECT_EQ(train.size(), header.size()) << train << "\n" << header;
    // Names longer than their column are not cut.
    const std::string long_name(40, 'x');
    EXPECT_NE(format_summary_row(long_name, long_name, s, SummaryScope::Test).find(long_name + " " + long_name),
              std::string::npos);
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
    EXPECT_EQ(m.sequences, a.sequences + b.sequences);
    EXPECT_EQ(m.test.max_bc_violation, std::max(a.test.max_bc_violation, b.test.max_bc_violation));
    EXPECT_EQ(m.test.final_rmse, (a.test.final_rmse + b.test.final_rmse) / 2.0);
    for (const SummaryMetric& metric : summary_metrics()) {
        const double va = metric.get(a), vb = metric.get(b), v = metric.get(m);
        switch (metric.aggregation) {
        case SummaryAggregation::Mean: EXPECT_DOUBLE_EQ(v, (va + vb) / 2.0) << metric.name; break;
        case SummaryAggregation::Max: EXPECT_EQ(v, std::max(va, vb)) << metric.name; break;
        case SummaryAggregation::Min: EXPECT_EQ(v, std::min(va, vb)) << metric.name; break;
        case SummaryAggregation::Sum: EXPECT_EQ(v, va + vb) << metric.name; break;
        }
    }
    const RolloutSummary empty = aggregate({});
    for (const SummaryMetric& metric : summary_metrics()) EXPECT_EQ(metric.get(empty), 0.0) << metric.name;
}

// Finding 1 of issue 10: the worst-case boundary violation over sequences started from
// 0 and skipped a NaN (std::max(0, NaN) == 0), so a diverged sequence printed as a
// perfect 0. Now NaN means "no frames aggregated" and the cell says "diverged".
TEST(SummarySchema, AggregateOfADivergedSequenceNeverReadsAsZero)
{
    RolloutSummary diverged = formatting_cases()[0];
    diverged.stable_horizon = 5;
    diverged.train.evaluated_frames = 3;
    diverged.test.evaluated_frames = 0;
    for (const SummaryMetric& m : summary_metrics()) {
        if (m.scope == SummaryScope::Test && !m.integer && std::string(m.field).rfind("frac_", 0) != 0)
            m.set(diverged, kNan);
    }
    const RolloutSummary alone = aggregate({diverged});
    EXPECT_TRUE(std::isnan(alone.test.max_bc_violation)) << "was 0 before issue 10";
    EXPECT_TRUE(std::isnan(alone.test.ke_ratio));
    for (const RolloutSummary& s : {alone, aggregate({diverged, diverged})}) {
        const std::vector<TableCell> cells = summary_table_cells(s, SummaryScope::Test);
        const std::vector<std::string> columns = summary_table_columns();
        for (size_t c = 0; c < cells.size(); ++c) {
            EXPECT_NE(cells[c].text, "0") << columns[c];
            if (columns[c].find("RMSE") != std::string::npos && columns[c].find("frames") == std::string::npos &&
                columns[c].find("first") == std::string::npos) {
                EXPECT_EQ(cells[c].text, "diverged @5") << columns[c];
            }
        }
        const std::vector<TableCell> train = summary_table_cells(s, SummaryScope::Train);
        for (size_t c = 0; c < train.size(); ++c) {
            if (columns[c] == "mean RMSE" || columns[c] == "max BC viol. (m)" || columns[c] == "KE ratio (free)") {
                EXPECT_NE(train[c].text.find("(diverged @5)"), std::string::npos) << columns[c] << ": " << train[c].text;
            }
        }
    }
    // Mixed with a stable sequence: the stable one's value, still marked as cut.
    const RolloutSummary mixed = aggregate({diverged, formatting_cases()[0]});
    EXPECT_EQ(mixed.test.max_bc_violation, formatting_cases()[0].test.max_bc_violation);
    EXPECT_EQ(mixed.stable_horizon, 5);
    EXPECT_LT(mixed.test.evaluated_frames, mixed.test.window_frames);
}

// ---- HDF5 ------------------------------------------------------------------------------

TEST(SummarySchema, EveryMetricRoundTripsThroughHdf5BitExactly)
{
    const std::string path = testing::fresh_dir("summary_schema") + "/summary.h5";
    const RolloutSummary s = distinct_summary();
    RolloutSummary odd = formatting_cases()[1];  // NaN and ±inf survive too
    odd.test.final_rmse = kNan;
    odd.test.mean_rmse = kInf;
    odd.train.max_bc_violation = -kInf;
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

TEST(SummarySchema, AFileWithoutTheWindowsIsRefusedAndMissingDoublesReadAsNan)
{
    const std::string path = testing::fresh_dir("summary_schema_legacy") + "/legacy.h5";
    {
        h5::File f = h5::File::create(path);
        // What save_rollouts wrote before the windows (issue 10): no train_frames.
        f.set_attribute("old", "frames", 10LL);
        f.set_attribute("old", "stable_horizon", 8LL);
        f.set_attribute("old", "mean_rmse", 0.5);
        // Every integer, but no doubles.
        for (const SummaryMetric& m : summary_metrics()) {
            if (m.integer) f.set_attribute("ints", m.name, 3LL);
        }
    }
    const h5::File f = h5::File::open(path);
    EXPECT_THROW(read_summary(f, "old"), IoError);
    const RolloutSummary ints = read_summary(f, "ints");
    EXPECT_EQ(ints.test.window_frames, 3);
    EXPECT_TRUE(std::isnan(ints.test.sted));
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
    results[1].summary.test.final_rmse = kNan;
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
