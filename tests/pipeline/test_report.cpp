// The comparison tables (issue 10): one row per method and window, diverged rows
// that never show a 0, and captions that say how sequences were combined.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/build_info.hpp"
#include "core/parallel.hpp"
#include "io/table.hpp"
#include "eval/metrics.hpp"
#include "pipeline/report.hpp"

namespace lb {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

/// A 60-frame rollout trained on 30 frames, RMSE 0.01, non-finite from `stop` (0: never).
RolloutSummary rollout_summary(Index stop, Index frames = 60)
{
    MatrixXd m = MatrixXd::Zero(frames, kNumMetricColumns);
    for (Index t = 0; t < m.rows(); ++t) {
        m(t, kRmse) = 0.01;
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

MethodResult method_result(const std::string& name, const std::string& method, const std::string& summary, bool paper,
                           std::vector<RolloutSummary> summaries)
{
    MethodResult m;
    m.name = name;
    m.method = method;
    m.summary = summary;
    m.paper_method = paper;
    m.summaries = std::move(summaries);
    return m;
}

SceneResult scene_with(std::vector<MethodResult> methods)
{
    SceneResult r;
    r.label = "cloth_small";
    r.scene_name = "cloth";
    r.dofs = 300;
    r.latent = 4;
    r.train_frames = 30;
    r.methods = std::move(methods);
    return r;
}

/// The Markdown table rows (lines starting with '|' after the header separator).
std::vector<std::string> body_rows(const std::string& markdown)
{
    std::vector<std::string> rows;
    size_t pos = markdown.find("|---");
    if (pos == std::string::npos) pos = markdown.find("| ---");
    pos = markdown.find('\n', pos);
    while (pos != std::string::npos && pos + 1 < markdown.size() && markdown[pos + 1] == '|') {
        const size_t end = markdown.find('\n', pos + 1);
        rows.push_back(markdown.substr(pos + 1, end - pos - 1));
        pos = end;
    }
    return rows;
}

TEST(Report, DivergedRowsReadAsDivergedAndWindowsAreApart)
{
    MethodResult good = method_result("ours", "latent_mlp", "self_supervised", true, {rollout_summary(0)});
    MethodResult bad = method_result("sup", "latent_mlp", "supervised_l2", false, {rollout_summary(20)});
    ExperimentConfig ex;
    ex.paper_tables = false;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_diverged";
    std::filesystem::remove_all(dir);
    const std::vector<std::string> written = write_tables(ex, {scene_with({good, bad})}, dir);
    ASSERT_EQ(written.size(), 1u);
    const std::string md = read_all(written[0]);
    const std::vector<std::string> rows = body_rows(md);
    ASSERT_EQ(rows.size(), 4u) << md;  // two methods × two windows
    EXPECT_NE(rows[0].find("train (frames 2-29)"), std::string::npos) << rows[0];
    EXPECT_NE(rows[1].find("test (frames >= 30)"), std::string::npos) << rows[1];
    // The diverged method: its training window cut at 20, its test window all "diverged".
    EXPECT_NE(rows[2].find("(diverged @20)"), std::string::npos) << rows[2];
    EXPECT_NE(rows[3].find("diverged @20"), std::string::npos) << rows[3];
    for (const std::string& row : {rows[2], rows[3]}) {
        EXPECT_EQ(row.find("| 0 |"), std::string::npos) << "a diverged row shows a 0: " << row;
    }
    EXPECT_NE(md.find("One test sequence per row"), std::string::npos);
}

TEST(Report, ThreadsFooterIsTheTimedRolloutsNotTheWriters)
{
    // Work units timed with -j 1 and merged by a -j 2 process once printed "threads: 2".
    set_num_threads(2);
    RolloutSummary one = rollout_summary(0);
    one.timing_threads = 1;
    ExperimentConfig ex;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_threads";
    std::filesystem::remove_all(dir);
    const SceneResult same = scene_with({method_result("ours", "latent_mlp", "self_supervised", true, {one, one})});
    for (const std::string& path : write_tables(ex, {same}, dir)) {
        const std::string md = read_all(path);
        EXPECT_NE(md.find("threads: 1 (as the rollouts were timed)"), std::string::npos) << path << "\n" << md;
        EXPECT_EQ(md.find("threads: 2"), std::string::npos) << path;
    }
    RolloutSummary two = one;
    two.timing_threads = 2;
    RolloutSummary old = one;
    old.timing_threads = kNan;  // a rollout file from before the count was recorded
    const SceneResult mixed = scene_with({method_result("ours", "latent_mlp", "self_supervised", true, {one, two, old})});
    const std::string md = read_all(write_tables(ex, {mixed}, dir + "_mixed").at(0));
    EXPECT_NE(md.find("threads: 1–2 (the rollouts were timed with different thread counts); not recorded"),
              std::string::npos)
        << md;
    set_num_threads(0);
}

TEST(Report, CaptionStatesHowSequencesAreCombined)
{
    // Before issue 10, multi-sequence rows mixed the worst-case horizon with mean errors
    // without saying so.
    MethodResult two = method_result("ours", "latent_mlp", "self_supervised", true, {rollout_summary(0), rollout_summary(45)});
    ExperimentConfig ex;
    ex.paper_tables = false;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_aggregation";
    std::filesystem::remove_all(dir);
    const std::string md = read_all(write_tables(ex, {scene_with({two})}, dir).at(0));
    EXPECT_NE(md.find("Rows combine 2 sequences: horizons are the worst case"), std::string::npos) << md;
    const std::vector<std::string> rows = body_rows(md);
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_NE(rows[1].find("(diverged @45)"), std::string::npos) << rows[1];
    EXPECT_NE(rows[1].find("45 of 60"), std::string::npos) << rows[1];  // 30 + 15 of 30 + 30 frames
}

// Finding 8 of issue 10: Table 1's "simulation" was the dataset's recorded Newton median
// (11.93 ms on the full cloth) while the full_space rollout of the same run measured
// 95.8 ms per frame. Now the column is the full_space rollout, measured like every other
// method; the dataset's figure stands apart as "dataset step".
TEST(Report, Table1SimulationIsTheFullSpaceRolloutOfTheSameRun)
{
    MethodResult ours = method_result("ours", "latent_mlp", "self_supervised", true, {rollout_summary(0)});
    RolloutSummary reference = rollout_summary(0);
    reference.integrate_ms = reference.total_ms = 95.8;
    reference.decode_ms = 0.0;
    MethodResult full = method_result("full_space", "full_space", "reference simulator", false, {reference});
    SceneResult r = scene_with({ours, full});
    r.dataset_step_ms = 11.93;
    ExperimentConfig ex;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_table1";
    std::filesystem::remove_all(dir);
    write_tables(ex, {r}, dir);
    const std::string md = read_all(dir + "/table1_timings.md");
    const std::vector<std::string> rows = body_rows(md);
    ASSERT_EQ(rows.size(), 1u) << md;
    const size_t sim = rows[0].find("95.8");
    const size_t dataset = rows[0].find("11.93");
    ASSERT_NE(sim, std::string::npos) << rows[0];
    ASSERT_NE(dataset, std::string::npos) << rows[0];
    EXPECT_LT(sim, dataset) << "the simulation column (4th) must hold the rollout's time: " << rows[0];
    EXPECT_NE(md.find("| dataset step (ms) |"), std::string::npos) << md;

    // Without a full_space rollout the column is empty, not the dataset's figure.
    SceneResult alone = scene_with({ours});
    alone.dataset_step_ms = 11.93;
    std::filesystem::remove_all(dir);
    write_tables(ex, {alone}, dir);
    const std::vector<std::string> rows_alone = body_rows(read_all(dir + "/table1_timings.md"));
    ASSERT_EQ(rows_alone.size(), 1u);
    // "| cloth_small | 300 | 4 | — | ...": the 4th cell.
    std::string cell = rows_alone[0];
    for (int k = 0; k < 3; ++k) cell = cell.substr(cell.find('|', 1));
    cell = cell.substr(1, cell.find('|', 1) - 1);
    EXPECT_EQ(cell.substr(cell.find_first_not_of(' '), cell.find_last_not_of(' ') - cell.find_first_not_of(' ') + 1),
              "—")
        << rows_alone[0];
}

/// The cell of column `title` in a Markdown row.
std::string cell_of(const std::string& markdown, const std::string& row, const std::string& title)
{
    auto split = [](const std::string& line) {
        std::vector<std::string> cells;
        size_t pos = 0;
        while ((pos = line.find('|', pos)) != std::string::npos && pos + 1 < line.size()) {
            const size_t end = line.find('|', pos + 1);
            if (end == std::string::npos) break;
            std::string c = line.substr(pos + 1, end - pos - 1);
            c.erase(0, c.find_first_not_of(' '));
            c.erase(c.find_last_not_of(' ') + 1);
            cells.push_back(c);
            pos = end;
        }
        return cells;
    };
    const size_t header = markdown.find("| method");
    const std::vector<std::string> titles = split(markdown.substr(header, markdown.find('\n', header) - header));
    const std::vector<std::string> cells = split(row);
    for (size_t k = 0; k < titles.size() && k < cells.size(); ++k) {
        if (titles[k] == title) return cells[k];
    }
    return "<no column " + title + ">";
}

TEST(Report, SeedsGiveAnIntervalOrARangeAndTheBudgetIsStated)
{
    // Five seeds: mean ± 95 % t-interval; the third seed diverges inside the test window.
    MethodResult five = method_result("ours", "latent_mlp", "self_supervised", true, {});
    for (int k = 0; k < 5; ++k) {
        five.seeds.push_back(std::uint64_t(k));
        five.per_seed.push_back(rollout_summary(k == 2 ? 45 : 0));
        five.summaries.push_back(five.per_seed.back());
        TrainingBudget b;
        b.recorded = true;
        b.epochs_run = 100;
        b.epochs_budget = 100;
        b.seconds = 10.0 + k;
        five.budgets.push_back(b);
    }
    // Three seeds: median [min, max]; stopped by a wall-clock cap.
    MethodResult three = method_result("sup", "latent_mlp", "supervised_l2", false, {});
    for (int k = 0; k < 3; ++k) {
        three.seeds.push_back(std::uint64_t(k));
        RolloutSummary s = rollout_summary(0);
        s.test.mean_rmse = 0.01 * (k + 1);
        three.per_seed.push_back(s);
        three.summaries.push_back(s);
        TrainingBudget b;
        b.recorded = true;
        b.epochs_run = 40;
        b.epochs_budget = 100;
        b.seconds = 60.0;
        b.max_seconds = 60.0;
        b.time_limited = true;
        three.budgets.push_back(b);
    }
    ExperimentConfig ex;
    ex.paper_tables = false;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_seeds";
    std::filesystem::remove_all(dir);
    const std::string md = read_all(write_tables(ex, {scene_with({five, three})}, dir).at(0));
    const std::vector<std::string> rows = body_rows(md);
    ASSERT_EQ(rows.size(), 4u) << md;
    EXPECT_NE(md.find("mean ± half-width of the 95 % Student-t interval over the 5 seeds"), std::string::npos) << md;
    // Test window of "ours": 4 seeds at 0.01 and one cut at 45 with 0.01: mean 0.01 ± 0.
    EXPECT_EQ(cell_of(md, rows[1], "mean RMSE"), "0.01 ± 0 (1/5 diverged, earliest @45)");
    // Horizons 60, 60, 45, 60, 60: mean 57, s = 6.71, t(4) = 2.776: ± 8.33.
    EXPECT_EQ(cell_of(md, rows[1], "stable (blow-up)"), "57 ± 8.33 (1/5 diverged, earliest @45)");
    EXPECT_EQ(cell_of(md, rows[0], "training"), "100/100 epochs, 12 s");
    EXPECT_EQ(cell_of(md, rows[3], "mean RMSE"), "0.02 [0.01, 0.03]");
    EXPECT_EQ(cell_of(md, rows[3], "training"), "40/100 epochs, 60 s (cap 60 s), time cap hit (3/3)");
    // One sequence per seed: the caption counts sequences, not seeds × sequences (the full
    // rods_rotate tables said "Rows combine 9 sequences" for 3 seeds of 3 sequences).
    EXPECT_NE(md.find("One test sequence per run; a row with seeds aggregates its runs ('seeds')."), std::string::npos)
        << md;
    EXPECT_EQ(md.find("Rows combine"), std::string::npos) << md;
    // the seeds' scope is stated: here the default, one autoencoder for every seed
    EXPECT_NE(md.find("Seed scope integrator: the seeds vary each method's initialisation"), std::string::npos) << md;
    three.summaries.push_back(three.summaries.back());  // each of the 3 seeds with 2 sequences
    three.summaries.push_back(three.summaries.back());
    three.summaries.push_back(three.summaries.back());
    const std::string md2 = read_all(write_tables(ex, {scene_with({three})}, dir + "_two").at(0));
    EXPECT_NE(md2.find("Each run (one seed's fit, or the one fit of a method without seeds) combines 2 sequences"),
              std::string::npos)
        << md2;

    // Horizons are counts: all their digits, not 1.5e+03 (5 seeds: ± with the same digits).
    MethodResult longer = method_result("long", "latent_mlp", "self_supervised", true, {});
    for (int k = 0; k < 5; ++k) {
        longer.seeds.push_back(std::uint64_t(k));
        longer.per_seed.push_back(rollout_summary(k == 0 ? 1234 : 0, 1500));
        longer.summaries.push_back(longer.per_seed.back());
    }
    std::filesystem::remove_all(dir);
    const std::string md_long = read_all(write_tables(ex, {scene_with({longer})}, dir).at(0));
    const std::vector<std::string> rows_long = body_rows(md_long);
    ASSERT_EQ(rows_long.size(), 2u) << md_long;
    // 1234, 1500, 1500, 1500, 1500: mean 1446.8, s = 118.96, t(4) = 2.776: ± 147.7.
    EXPECT_EQ(cell_of(md_long, rows_long[1], "stable (blow-up)"), "1447 ± 147.7 (1/5 diverged, earliest @1234)");
    // Test window from frame 30: 1204 and 4 × 1470 frames before the horizons.
    EXPECT_EQ(cell_of(md_long, rows_long[1], "frames aggregated"), "1417 ± 147.7");

    // An ablation's table is written only for scenes that ran all of its methods.
    ExperimentConfig with_ablation;
    with_ablation.paper_tables = false;
    with_ablation.ablations.push_back({"supervision", "Supervised vs self-supervised", {"ours", "sup"}});
    std::filesystem::remove_all(dir);
    write_tables(with_ablation, {scene_with({five, three})}, dir);
    EXPECT_TRUE(std::filesystem::exists(dir + "/ablation_supervision_cloth_small.md"));
    std::filesystem::remove_all(dir);
    write_tables(with_ablation, {scene_with({five})}, dir);
    EXPECT_FALSE(std::filesystem::exists(dir + "/ablation_supervision_cloth_small.md"));
}

/// The value of `column` in the first CSV row whose method and window start as given.
double csv_value(const Table& t, const std::string& method, const std::string& window, const std::string& column)
{
    size_t m = t.columns.size(), w = m, c = m;
    for (size_t k = 0; k < t.columns.size(); ++k) {
        if (t.columns[k] == "method") m = k;
        if (t.columns[k] == "window") w = k;
        if (t.columns[k] == column) c = k;
    }
    if (c == t.columns.size()) ADD_FAILURE() << "no column " << column;
    for (const auto& row : t.rows) {
        if (c < row.size() && row[m].text == method && row[w].text.rfind(window, 0) == 0)
            return row[c].value ? *row[c].value : std::numeric_limits<double>::infinity();
    }
    ADD_FAILURE() << "no row " << method << " / " << window;
    return 0.0;
}

TEST(Report, CsvTwinCountsSeedsAndDivergenceWhereTheMarkdownSaysSo)
{
    // Three seeds, one of which blows up at frame 20, before the test window (frames >= 30);
    // and a method without seeds that blows up at 20 too.
    MethodResult three = method_result("ours", "latent_mlp", "self_supervised", true, {});
    for (int k = 0; k < 3; ++k) {
        three.seeds.push_back(std::uint64_t(k));
        three.per_seed.push_back(rollout_summary(k == 1 ? 20 : 0));
        three.summaries.push_back(three.per_seed.back());
        three.summary_seeds.push_back(k);
        three.sequences.push_back("test");
    }
    MethodResult single = method_result("sup", "latent_mlp", "supervised_l2", false, {rollout_summary(20)});
    single.fit_version = 4;
    ExperimentConfig ex;
    ex.name = "csv_twin";
    ex.paper_tables = false;
    const std::string dir = std::string(LB_TEST_TMP_DIR) + "/report_csv_twin";
    std::filesystem::remove_all(dir);
    const std::string md = read_all(write_tables(ex, {scene_with({three, single})}, dir).at(0));
    const std::vector<std::string> rows = body_rows(md);
    ASSERT_EQ(rows.size(), 4u) << md;
    // The Markdown: the test-window error over the two seeds that reached it, and says so.
    EXPECT_EQ(cell_of(md, rows[1], "mean RMSE"), "0.01 [0.01, 0.01] (2 of 3 seeds; 1/3 diverged, earliest @20)");
    EXPECT_EQ(cell_of(md, rows[1], "seeds"), "3");
    EXPECT_EQ(cell_of(md, rows[3], "mean RMSE"), "diverged @20");

    // The CSV, read as a script would: the counts and flags are there, not a bare number.
    const Table csv = read_csv(dir + "/methods_cloth_small.csv");
    EXPECT_EQ(csv_value(csv, "ours", "test", "n_seeds"), 3.0);
    EXPECT_EQ(csv_value(csv, "ours", "test", "n_diverged"), 1.0);
    EXPECT_EQ(csv_value(csv, "ours", "test", "diverged_at"), 20.0);
    EXPECT_EQ(csv_value(csv, "ours", "test", "window_diverged"), 1.0);
    EXPECT_EQ(csv_value(csv, "ours", "test", "mean_rmse_n"), 2.0);
    EXPECT_DOUBLE_EQ(csv_value(csv, "ours", "test", "mean_rmse_median"), 0.01);
    EXPECT_EQ(csv_value(csv, "ours", "test", "stable_horizon_min"), 20.0);
    EXPECT_EQ(csv_value(csv, "ours", "test", "stable_horizon_max"), 60.0);
    EXPECT_EQ(csv_value(csv, "sup", "test", "n_seeds"), 1.0);
    EXPECT_EQ(csv_value(csv, "sup", "test", "n_diverged"), 1.0);
    EXPECT_EQ(csv_value(csv, "sup", "train", "window_diverged"), 1.0);
    EXPECT_TRUE(std::isnan(csv_value(csv, "sup", "test", "mean_rmse_median")));  // "diverged @20" in Markdown
    EXPECT_EQ(csv_value(csv, "sup", "test", "mean_rmse_n"), 0.0);
    EXPECT_EQ(csv_value(csv, "ours", "train", "window_diverged"), 1.0);  // cut inside the training window

    // The tidy rollouts: one row per seed and window, the flag on the seed that blew up.
    const Table tidy = read_csv(dir + "/rollouts_cloth_small.csv");
    ASSERT_EQ(tidy.rows.size(), 8u);  // (3 seeds + 1 run) × 2 windows
    int flagged = 0;
    for (const auto& row : tidy.rows) flagged += row[tidy.columns.size() - 2].text == "1";
    EXPECT_EQ(flagged, 4);  // seed 1 and `sup`, both windows

    // Provenance: every table's notes name the commit, the suite and the fit versions.
    EXPECT_NE(md.find(std::string("commit: ") + build_commit_short()), std::string::npos) << md;
    EXPECT_NE(md.find("suite: csv_twin"), std::string::npos) << md;
    EXPECT_NE(md.find("fit versions: ours 0, sup 4"), std::string::npos) << md;
    EXPECT_NE(read_all(dir + "/methods_cloth_small.csv").find("# suite: csv_twin"), std::string::npos);
    write_provenance(ex, {scene_with({three, single})}, dir);
    const std::string json = read_all(dir + "/provenance.json");
    EXPECT_NE(json.find(std::string("\"commit\": \"") + build_commit() + "\""), std::string::npos) << json;
    EXPECT_NE(json.find("\"fit_versions\": {\"ours\": 0, \"sup\": 4}"), std::string::npos) << json;
}

} // namespace
} // namespace lb
