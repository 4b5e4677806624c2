// The regression gate (pipeline/regress.hpp) on tables written by the real table
// writer (write_tables: methods_*.csv and the tidy rollouts_*.csv): an identical
// run passes, a degraded method is caught and named, an improvement is not a failure,
// missing and new rows are reported, the seed range is widened by the tolerance, the
// JUnit XML holds one testcase per row, and bad input names the file.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>

#include "core/error.hpp"
#include "eval/metrics.hpp"
#include "io/table.hpp"
#include "pipeline/regress.hpp"
#include "pipeline/regress_report.hpp"
#include "pipeline/report.hpp"

namespace fs = std::filesystem;

namespace lb {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// A 60-frame rollout trained on 30 frames with relative RMSE `rmse`, non-finite from
/// `stop` (0: never).
RolloutSummary rollout(double rmse, Index stop = 0, Index frames = 60)
{
    MatrixXd m = MatrixXd::Zero(frames, kNumMetricColumns);
    for (Index t = 0; t < m.rows(); ++t) {
        m(t, kRmse) = rmse;
        m(t, kBcViolation) = 2e-3;
        m(t, kKineticFree) = 0.5;
        m(t, kKineticFreeGt) = 1.0;
        m(t, kResidual) = 0.2;
        m(t, kStedSpatial) = 0.01;
        m(t, kIntegrateSeconds) = m(t, kDecodeSeconds) = 1e-4;
    }
    if (stop > 0) m.bottomRows(m.rows() - stop).setConstant(kNan);
    return summarize(m, 1.0, 30);
}

/// A method row: one summary per seed (seeds 0, 1, ...), or one without a seed.
MethodResult method(const std::string& name, const std::vector<RolloutSummary>& per_seed, bool seeded = true)
{
    MethodResult m;
    m.name = name;
    m.method = "latent_mlp";
    m.summary = name;
    for (size_t k = 0; k < per_seed.size(); ++k) {
        m.summaries.push_back(per_seed[k]);
        m.sequences.push_back("release");
        m.summary_seeds.push_back(seeded ? static_cast<long long>(k) : -1);
        if (seeded) {
            m.seeds.push_back(k);
            m.per_seed.push_back(per_seed[k]);
        }
    }
    return m;
}

/// A run directory whose tables/ the real writer filled with one scene.
std::string write_run(const std::string& name, std::vector<MethodResult> methods)
{
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/regress/" + name;
    fs::remove_all(dir);
    SceneResult r;
    r.label = "cantilever_small";
    r.scene_name = "cantilever";
    r.dofs = 300;
    r.latent = 4;
    r.train_frames = 30;
    r.methods = std::move(methods);
    ExperimentConfig ex;
    ex.paper_tables = false;
    write_tables(ex, {r}, dir + "/tables");
    return dir;
}

/// The usual baseline: ours (3 seeds, stable), a supervised method that diverges at 40,
/// linear PCA (no seed).
std::vector<MethodResult> baseline_methods()
{
    return {method("ours", {rollout(0.010), rollout(0.012), rollout(0.014)}),
            method("supervised", {rollout(0.05, 40), rollout(0.05, 45), rollout(0.05, 50)}),
            method("pca", {rollout(0.02)}, false)};
}

GateReport gate(const std::string& baseline, const std::string& run, const GateOptions& o = default_gate_options())
{
    return compare_gate_rows(load_gate_rows(baseline), load_gate_rows(run), o);
}

const GateRowResult& row_of(const GateReport& r, const std::string& method, const std::string& window)
{
    const auto it = std::find_if(r.rows.begin(), r.rows.end(), [&](const GateRowResult& x) {
        return x.key.method == method && x.key.window == window;
    });
    if (it == r.rows.end()) throw std::runtime_error("no row " + method + " / " + window);
    return *it;
}

const GateMetricResult* metric_of(const GateRowResult& r, const std::string& field)
{
    for (const GateMetricResult& m : r.metrics)
        if (m.field == field) return &m;
    return nullptr;
}

std::ptrdiff_t occurrences(const std::string& text, const std::string& what)
{
    std::ptrdiff_t n = 0;
    for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
    return n;
}

TEST(Regress, ObservationsTableIsOneRowPerSeedSequenceAndWindow)
{
    const std::string dir = write_run("observations", baseline_methods());
    const Table t = read_csv(dir + "/tables/rollouts_cantilever_small.csv");
    EXPECT_EQ(t.rows.size(), (3u + 3u + 1u) * 2u);  // seeds × windows, pca once per window
    for (const char* column : {"scene", "method", "sweep point", "seed", "sequence", "window", "stable_horizon",
                               "mean_rmse", "max_bc_violation", "diverged", "diverged_at"}) {
        EXPECT_NE(std::find(t.columns.begin(), t.columns.end(), column), t.columns.end()) << column;
    }
    const size_t diverged = size_t(std::find(t.columns.begin(), t.columns.end(), "diverged") - t.columns.begin());
    const size_t at = size_t(std::find(t.columns.begin(), t.columns.end(), "diverged_at") - t.columns.begin());
    int n_diverged = 0;
    for (const auto& row : t.rows) {
        if (row[1].text == "supervised") {
            EXPECT_EQ(*row[diverged].value, 1.0);
            EXPECT_GE(*row[at].value, 40.0);
            ++n_diverged;
        } else {
            EXPECT_EQ(*row[diverged].value, 0.0) << row[1].text;
            EXPECT_TRUE(std::isnan(*row[at].value));
        }
    }
    EXPECT_EQ(n_diverged, 6);
}

TEST(Regress, IdenticalRunPasses)
{
    const std::string base = write_run("identical_base", baseline_methods());
    const std::string run = write_run("identical_run", baseline_methods());
    const GateReport r = gate(base, run);
    ASSERT_EQ(r.rows.size(), 6u);  // three methods × two windows
    EXPECT_FALSE(r.failed());
    EXPECT_EQ(r.count(GateVerdict::Unchanged), 6);
    for (const GateRowResult& row : r.rows) EXPECT_FALSE(row.metrics.empty()) << row.key.text();
    // every default metric and the divergence check were compared on ours
    const GateRowResult& ours = row_of(r, "ours", "test");
    for (const char* f : {"diverged", "stable_horizon", "horizon_loose", "mean_rmse", "final_rmse", "max_bc_violation"})
        EXPECT_NE(metric_of(ours, f), nullptr) << f;
    EXPECT_NE(gate_markdown(r, run, base).find("**PASS**"), std::string::npos);
}

TEST(Regress, DivergingMethodIsCaughtAndNamed)
{
    const std::string base = write_run("diverge_base", baseline_methods());
    std::vector<MethodResult> now = baseline_methods();
    now[0] = method("ours", {rollout(0.010), rollout(0.012, 20), rollout(0.014)});  // one seed blows up at 20
    const GateReport r = gate(base, write_run("diverge_run", now));
    EXPECT_TRUE(r.failed());
    for (const char* window : {"train", "test"}) {
        const GateRowResult& ours = row_of(r, "ours", window);
        EXPECT_EQ(ours.verdict, GateVerdict::Regression) << window;
        ASSERT_NE(metric_of(ours, "diverged"), nullptr);
        EXPECT_EQ(metric_of(ours, "diverged")->verdict, GateVerdict::Regression);
        EXPECT_EQ(metric_of(ours, "diverged")->reason, "newly diverged");
        EXPECT_EQ(metric_of(ours, "diverged")->now, "1/3 seeds");
    }
    // the median horizon (60, 20, 60 -> 60) did not move, but one seed now diverges: the
    // divergence check catches it alone; the others are unchanged
    EXPECT_EQ(row_of(r, "supervised", "test").verdict, GateVerdict::Unchanged);
    EXPECT_EQ(row_of(r, "pca", "test").verdict, GateVerdict::Unchanged);
    EXPECT_EQ(r.count(GateVerdict::Regression), 2);
    const std::string md = gate_markdown(r, "run", "base");
    EXPECT_NE(md.find("**FAIL**"), std::string::npos);
    EXPECT_NE(md.find("- cantilever_small / ours / test: diverged 0/3 seeds -> 1/3 seeds (newly diverged)"),
              std::string::npos)
        << md;
}

TEST(Regress, DriftingAndShorterHorizonsAreCaught)
{
    const std::string base = write_run("drift_base", baseline_methods());
    std::vector<MethodResult> now = baseline_methods();
    // ours drifts: every seed's RMSE doubled (above 0.014 · 1.25 + 1e-4); the supervised
    // method blows up earlier (its worst seed at 40, now every seed at 30)
    now[0] = method("ours", {rollout(0.020), rollout(0.024), rollout(0.028)});
    now[1] = method("supervised", {rollout(0.05, 30), rollout(0.05, 30), rollout(0.05, 30)});
    const GateReport r = gate(base, write_run("drift_run", now));
    EXPECT_TRUE(r.failed());
    const GateRowResult& ours = row_of(r, "ours", "test");
    EXPECT_EQ(ours.verdict, GateVerdict::Regression);
    EXPECT_EQ(metric_of(ours, "mean_rmse")->verdict, GateVerdict::Regression);
    EXPECT_NE(metric_of(ours, "mean_rmse")->reason.find("above the band's top"), std::string::npos);
    EXPECT_EQ(metric_of(ours, "diverged")->verdict, GateVerdict::Unchanged);
    const GateRowResult& sup = row_of(r, "supervised", "train");
    EXPECT_EQ(metric_of(sup, "stable_horizon")->verdict, GateVerdict::Regression);
    EXPECT_EQ(metric_of(sup, "stable_horizon")->change, "-15 frames");  // median 45 -> 30
    EXPECT_EQ(metric_of(sup, "diverged")->verdict, GateVerdict::Unchanged);  // 3/3 before and after
    EXPECT_EQ(row_of(r, "pca", "test").verdict, GateVerdict::Unchanged);
}

TEST(Regress, SeedRangeIsWidenedByTheTolerance)
{
    const std::string base = write_run("band_base", baseline_methods());
    // band top: 0.014 · 1.25 + 1e-4 = 0.0176; the run's median counts
    std::vector<MethodResult> inside = baseline_methods();
    inside[0] = method("ours", {rollout(0.017), rollout(0.017), rollout(0.030)});
    EXPECT_EQ(row_of(gate(base, write_run("band_inside", inside)), "ours", "test").verdict, GateVerdict::Unchanged);
    std::vector<MethodResult> outside = baseline_methods();
    outside[0] = method("ours", {rollout(0.018), rollout(0.018), rollout(0.010)});
    EXPECT_EQ(row_of(gate(base, write_run("band_outside", outside)), "ours", "test").verdict, GateVerdict::Regression);
    // a looser tolerance file lets the same run pass
    const std::string tolerance = std::string(LB_TEST_TMP_DIR) + "/regress/loose.toml";
    std::ofstream(tolerance) << "[metrics.mean_rmse]\nrelative = 0.5\n[metrics.final_rmse]\nrelative = 0.5\n";
    const GateOptions loose = load_gate_options(tolerance);
    EXPECT_EQ(row_of(gate(base, write_run("band_outside", outside), loose), "ours", "test").verdict,
              GateVerdict::Unchanged);
}

TEST(Regress, ImprovementIsNotAFailure)
{
    const std::string base = write_run("improve_base", baseline_methods());
    std::vector<MethodResult> now = baseline_methods();
    now[0] = method("ours", {rollout(0.005), rollout(0.005), rollout(0.006)});        // more accurate
    now[1] = method("supervised", {rollout(0.05), rollout(0.05), rollout(0.05)});    // no longer diverges
    const GateReport r = gate(base, write_run("improve_run", now));
    EXPECT_FALSE(r.failed());
    EXPECT_EQ(r.count(GateVerdict::Regression), 0);
    EXPECT_EQ(row_of(r, "ours", "test").verdict, GateVerdict::Improvement);
    EXPECT_EQ(metric_of(row_of(r, "ours", "test"), "mean_rmse")->verdict, GateVerdict::Improvement);
    const GateRowResult& sup = row_of(r, "supervised", "test");
    EXPECT_EQ(sup.verdict, GateVerdict::Improvement);
    EXPECT_EQ(metric_of(sup, "diverged")->reason, "no longer diverges");
    EXPECT_EQ(metric_of(sup, "stable_horizon")->verdict, GateVerdict::Improvement);
    EXPECT_NE(gate_markdown(r, "run", "base").find("**PASS**"), std::string::npos);
}

TEST(Regress, MissingAndNewRowsAreReported)
{
    const std::string base = write_run("missing_base", baseline_methods());
    std::vector<MethodResult> now = baseline_methods();
    now.erase(now.begin() + 1);                                       // the supervised method is gone
    now.push_back(method("mine", {rollout(0.01)}));                   // and a new one
    const std::string run = write_run("missing_run", now);
    GateReport r = gate(base, run);
    EXPECT_EQ(r.count(GateVerdict::Missing), 2);
    EXPECT_EQ(r.count(GateVerdict::New), 2);
    EXPECT_EQ(row_of(r, "supervised", "test").verdict, GateVerdict::Missing);
    EXPECT_EQ(row_of(r, "mine", "test").verdict, GateVerdict::New);
    EXPECT_FALSE(r.failed());  // reported only, by default
    const std::string md = gate_markdown(r, run, base);
    EXPECT_NE(md.find("Missing in the run"), std::string::npos);
    EXPECT_NE(md.find("- cantilever_small / supervised / test"), std::string::npos) << md;
    EXPECT_NE(md.find("- cantilever_small / mine / train"), std::string::npos) << md;
    GateOptions strict = default_gate_options();
    strict.fail_on_missing = true;
    EXPECT_TRUE(gate(base, run, strict).failed());
}

TEST(Regress, JunitHasOneTestcasePerRow)
{
    const std::string base = write_run("junit_base", baseline_methods());
    std::vector<MethodResult> now = baseline_methods();
    now[0] = method("ours", {rollout(0.03), rollout(0.03), rollout(0.03)});
    now.erase(now.begin() + 2);
    const GateReport r = gate(base, write_run("junit_run", now));
    const std::string xml = gate_junit(r);
    const std::ptrdiff_t testcases = occurrences(xml, "<testcase ");
    EXPECT_EQ(testcases, std::ptrdiff_t(r.rows.size()));
    EXPECT_EQ(r.rows.size(), 6u);
    const std::ptrdiff_t failures = occurrences(xml, "<failure ");
    EXPECT_EQ(failures, 2);  // ours, both windows
    EXPECT_NE(xml.find("<skipped message=\"row in the baseline, missing in the run\"/>"), std::string::npos);
    EXPECT_NE(xml.find("name=\"ours / test\""), std::string::npos);
    EXPECT_EQ(xml_escape("a<b & \"c\"'"), "a&lt;b &amp; &quot;c&quot;&apos;");
}

TEST(Regress, MethodsTablesStandInForObservations)
{
    // A results/ folder published before rollouts_*.csv existed: the methods tables.
    const std::string base = write_run("methods_base", baseline_methods());
    fs::remove(base + "/tables/rollouts_cantilever_small.csv");
    const GateReport same = gate(base, base);
    EXPECT_FALSE(same.failed());
    EXPECT_EQ(same.count(GateVerdict::Unchanged), 6);
    // Today's methods CSV is the Markdown's machine-readable twin: it counts diverged seeds.
    EXPECT_NE(metric_of(row_of(same, "ours", "test"), "diverged"), nullptr);
    std::vector<MethodResult> now = baseline_methods();
    now[1] = method("supervised", {rollout(0.05, 20), rollout(0.05, 20), rollout(0.05, 20)});
    const GateReport worse = gate(base, write_run("methods_run", now));
    EXPECT_TRUE(worse.failed());
    EXPECT_EQ(metric_of(row_of(worse, "supervised", "test"), "stable_horizon")->verdict, GateVerdict::Regression);
}

TEST(Regress, BadInputNamesTheFile)
{
    const std::string empty = std::string(LB_TEST_TMP_DIR) + "/regress/empty";
    fs::remove_all(empty);
    fs::create_directories(empty);
    try {
        load_gate_rows(empty);
        FAIL() << "an empty folder was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(empty), std::string::npos) << e.what();
    }
    EXPECT_THROW(load_gate_rows(empty + "/none"), IoError);

    const std::string dir = write_run("bad_csv", baseline_methods());
    const std::string file = dir + "/tables/rollouts_cantilever_small.csv";
    std::ofstream(file, std::ios::app) << "cantilever_small,ours,only three\n";
    try {
        load_gate_rows(dir);
        FAIL() << "a short row was accepted";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("3 fields where the header has"), std::string::npos) << e.what();
    }

    const std::string tolerance = std::string(LB_TEST_TMP_DIR) + "/regress/bad_tolerance.toml";
    std::ofstream(tolerance) << "[metrics.total_ms]\nrelative = 0.1\n";
    try {
        load_gate_options(tolerance);
        FAIL() << "a timing metric was accepted";
    } catch (const ConfigError& e) {
        EXPECT_NE(std::string(e.what()).find("total_ms"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(tolerance), std::string::npos) << e.what();
    }
    std::ofstream(tolerance) << "[metrics.mean_rmse]\nrelativ = 0.1\n";
    EXPECT_THROW(load_gate_options(tolerance), ConfigError);
    std::ofstream(tolerance) << "[metrics.mean_rmse]\nrelative = -0.1\n";
    EXPECT_THROW(load_gate_options(tolerance), ConfigError);
    std::ofstream(tolerance) << "[metrics.final_rmse]\ngate = false\n";
    const GateOptions o = load_gate_options(tolerance);
    EXPECT_TRUE(std::none_of(o.metrics.begin(), o.metrics.end(), [](const GateMetric& m) { return m.field == "final_rmse"; }));
    EXPECT_EQ(o.metrics.size(), default_gate_metrics().size() - 1);
}

} // namespace
} // namespace lb
