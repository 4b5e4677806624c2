// The suite page (pipeline/html_page.hpp) of a folder made by hand: tables from their
// structured twins (diverged cells marked, seeds from the observations, everything escaped),
// a CSV-only table read and flagged, figures and videos by relative path and by scene,
// provenance, the listing page; a folder without a methods table refused. The browser test
// (tests/scripts/test_suite_page.py, label browser) opens a real run's page.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "io/table.hpp"
#include "io/table_data.hpp"
#include "pipeline/html_page.hpp"
#include "support/cli_runner.hpp"

namespace {

namespace fs = std::filesystem;
using lb::Table;
using lb::TableCell;

std::string read_all(const std::string& path)
{
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

size_t count(const std::string& text, const std::string& what)
{
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

/// A suite folder: scene "a" with every table as a twin, scene "b" with its methods table
/// as CSV only; figures, videos, an experiment.toml.
std::string make_suite(const std::string& name)
{
    const std::string dir = lb::testing::fresh_dir(name) + "/suite";
    fs::create_directories(dir + "/tables");
    fs::create_directories(dir + "/figures/a");
    fs::create_directories(dir + "/videos");
    lb::testing::write_file(dir + "/experiment.toml", "name = \"demo <suite>\"\ndescription = \"a & b\"\n");
    Table m;
    m.title = "Methods on a";
    m.caption = "caption of a";
    m.columns = {"method", "window", "stable (blow-up)", "mean RMSE"};
    m.add_row({"ours", "test", TableCell("diverged @12", 12.0), TableCell("0.2 (diverged @12)", 0.2)});
    m.add_row({"pca", "test", TableCell("50 / 50", 50.0), TableCell("0.01", 0.01)});
    m.add_row({"<script>alert(1)</script>", "test", TableCell("50 / 50", 50.0), TableCell("0.03", 0.03)});
    m.add_note("machine: hand-made");
    lb::write_table_files(m, dir + "/tables/methods_a");
    lb::write_table_data(m, dir + "/tables/methods_a");
    Table d;
    d.title = "Deviations from the paper's recipe (a)";
    d.columns = {"key", "status"};
    d.add_row({"epochs", "deviates"});
    lb::write_table_data(d, dir + "/tables/deviations_a");
    Table obs;
    obs.columns = {"scene", "method", "sweep point", "seed", "sequence", "window"};
    for (int seed = 0; seed < 3; ++seed)
        obs.add_row({"a", "ours", "", TableCell(std::to_string(seed), seed), "s", "test"});
    obs.add_row({"a", "pca", "", TableCell::missing("nan"), "s", "test"});
    lb::write_csv(obs, dir + "/tables/rollouts_a.csv");
    Table b = m;
    b.title = "Methods on b";
    lb::write_csv(b, dir + "/tables/methods_b.csv");
    for (const char* f : {"figures/a_filmstrip.png", "figures/a/release_rmse.png", "figures/a/training_loss.png",
                          "figures/loose figure.png", "videos/a.mp4", "videos/a_extra.mp4"})
        lb::testing::write_file(dir + "/" + f, "not really an image");
    return dir;
}

TEST(HtmlPage, ShowsEveryTableFigureAndVideoOfTheFolder)
{
    const std::string dir = make_suite("html_page");
    const std::string path = lb::write_suite_page(dir);
    EXPECT_EQ(path, dir + "/index.html");
    const std::string html = read_all(path);
    // escaped everywhere: title, description, cells
    EXPECT_NE(html.find("<h1>demo &lt;suite&gt;</h1>"), std::string::npos);
    EXPECT_NE(html.find("a &amp; b"), std::string::npos);
    EXPECT_EQ(html.find("<script>alert"), std::string::npos);
    EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
    EXPECT_EQ(count(html, "<script>"), 1u);  // the sorting script only
    // diverged cells marked (the stable horizon and the error cut by it), others not
    EXPECT_EQ(count(html, "class=\"num diverged\""), 2u);  // scene a: the horizon and the error it cut
    EXPECT_NE(html.find("<td class=\"num diverged\" data-v=\"12\""), std::string::npos);
    // seeds from the observations: ours three, pca none
    EXPECT_NE(html.find(">3 (0, 1, 2)</td>"), std::string::npos);
    EXPECT_NE(html.find(">1 (no seed)</td>"), std::string::npos);
    // scene a's figures and video by relative path, in their sections; the rest under "other"
    for (const char* s : {"src=\"figures/a_filmstrip.png\"", "src=\"figures/a/release_rmse.png\"",
                          "src=\"figures/a/training_loss.png\"", "src=\"videos/a.mp4\"", "src=\"videos/a_extra.mp4\"",
                          "src=\"figures/loose%20figure.png\""})
        EXPECT_NE(html.find(s), std::string::npos) << s;
    EXPECT_LT(html.find("Training curves"), html.find("training_loss.png"));
    EXPECT_LT(html.find("Per-metric plots"), html.find("release_rmse.png"));
    EXPECT_GT(html.find("videos/a_extra.mp4"), html.find("Other outputs"));
    EXPECT_NE(html.find("Deviations from the paper&#39;s recipe (a)"), std::string::npos);
    // scene b's methods table came from its CSV: flagged, numbers shown to 4 digits
    EXPECT_NE(html.find("id=\"scene-b\""), std::string::npos);
    EXPECT_NE(html.find("read from their CSV"), std::string::npos);
    EXPECT_NE(html.find("Read from the CSV"), std::string::npos);
    // no network: no absolute URL anywhere
    EXPECT_EQ(html.find("http://"), std::string::npos);
    EXPECT_EQ(html.find("https://"), std::string::npos);
}

TEST(HtmlPage, CsvOnlyTablesCannotMarkDivergedCells)
{
    // The CSV writes 12 for "diverged @12": scene b's table shows the number, unmarked.
    const std::string dir = make_suite("html_page_csv");
    const std::string html = read_all(lb::write_suite_page(dir));
    const size_t b = html.find("id=\"scene-b\"");
    ASSERT_NE(b, std::string::npos);
    const std::string scene_b = html.substr(b, html.find("</section>", b) - b);
    EXPECT_EQ(scene_b.find("diverged\""), std::string::npos);
    EXPECT_NE(scene_b.find("data-v=\"12\">12</td>"), std::string::npos);
    const std::string scene_a = html.substr(0, b);
    EXPECT_EQ(count(scene_a, "class=\"num diverged\""), 2u);
}

TEST(HtmlPage, ProvenanceFromTheRunOrFromTheFolder)
{
    const std::string dir = make_suite("html_page_provenance");
    // without provenance.json: the tables' own note, the command not recorded
    std::string html = read_all(lb::write_suite_page(dir));
    EXPECT_NE(html.find("not recorded (no provenance.json"), std::string::npos);
    EXPECT_NE(html.find("machine: hand-made"), std::string::npos);
    // a run's provenance.json (as write_provenance writes it): every entry shown, escaped
    {
        std::ofstream out(dir + "/provenance.json");
        out << "{\n  \"format\": \"latentbench.provenance/1\",\n  \"suite\": \"demo\",\n"
               "  \"suite_file\": \"experiments/demo.toml\",\n  \"suite_hash\": \"fnv1a64:0123456789abcdef\",\n"
               "  \"commit\": \"abc123\",\n  \"dirty\": true,\n  \"seeds\": [0, 1],\n  \"threads\": 2,\n"
               "  \"fit_versions\": {\"ours\": 3},\n"
               "  \"command\": [\"latentbench\", \"run\", \"x.toml\", \"-o\", \"<dir>\"],\n"
               "  \"machine\": \"m\",\n  \"date\": \"2026-01-01 00:00 UTC\"\n}\n";
    }
    html = read_all(lb::write_suite_page(dir));
    EXPECT_NE(html.find("abc123 (uncommitted changes)"), std::string::npos) << html;
    EXPECT_NE(html.find("latentbench run x.toml -o &lt;dir&gt;"), std::string::npos);
    EXPECT_NE(html.find("experiments/demo.toml (fnv1a64:0123456789abcdef)"), std::string::npos);
    EXPECT_NE(html.find("ours 3"), std::string::npos);
    EXPECT_NE(html.find("2026-01-01 00:00 UTC"), std::string::npos);
    // a retrofitted one: nulls read "not recorded"; a damaged one is an error naming the file
    {
        std::ofstream out(dir + "/provenance.json");
        out << "{\"commit\": \"def456\", \"command\": null}";
    }
    html = read_all(lb::write_suite_page(dir));
    EXPECT_NE(html.find("<dd>not recorded</dd>"), std::string::npos) << html;
    {
        std::ofstream out(dir + "/provenance.json");
        out << "{\"commit\": ";
    }
    try {
        lb::write_suite_page(dir);
        ADD_FAILURE() << "a damaged provenance.json was accepted";
    } catch (const lb::IoError& e) {
        EXPECT_NE(std::string(e.what()).find("provenance.json: malformed JSON"), std::string::npos) << e.what();
    }
}

TEST(HtmlPage, ListingLinksEverySuitePage)
{
    const std::string dir = make_suite("html_page_listing");
    const std::string root = fs::path(dir).parent_path().string();
    EXPECT_THROW(lb::write_suite_listing({dir}, root + "/index.html"), lb::IoError);  // no index.html yet
    lb::write_suite_page(dir);
    const std::string html = read_all(lb::write_suite_listing({dir}, root + "/index.html"));
    EXPECT_NE(html.find("href=\"suite/index.html\""), std::string::npos) << html;
    EXPECT_NE(html.find("href=\"suite/index.html#scene-a\""), std::string::npos);
    EXPECT_NE(html.find("demo &lt;suite&gt;"), std::string::npos);
}

TEST(HtmlPage, RefusesAFolderWithoutAMethodsTable)
{
    const std::string dir = lb::testing::fresh_dir("html_page_empty");
    try {
        lb::write_suite_page(dir);
        FAIL() << "no error";
    } catch (const lb::IoError& e) {
        EXPECT_NE(std::string(e.what()).find(dir), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("no methods table"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir + "/index.html"));
    EXPECT_THROW(lb::write_suite_page(dir + "/missing"), lb::IoError);
}

} // namespace
