// Table writers (Markdown, CSV, LaTeX), atomic writing, provenance, the paper's
// published tables, and scripts/plot_rollouts.py on a rollout file written here.
#include "lb_paths.hpp"
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <regex>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/process.hpp"
#include "core/parallel.hpp"
#include "eval/metrics.hpp"
#include "paper/paper_numbers.hpp"
#include "io/hdf5.hpp"
#include "io/table.hpp"
#include "support/cli_runner.hpp"

namespace fs = std::filesystem;
using lb::Table;
using lb::TableCell;

namespace {

Table demo_table()
{
    Table t;
    t.title = "Demo table";
    t.caption = "A small example.";
    t.label = "tab:demo";
    t.columns = {"method", "rmse", "time"};
    t.add_row({"ours", TableCell::fixed(0.12345, 3), TableCell::fixed(0.72, 3, "ms")});
    t.add_row({"a|b, \"c\"", TableCell::significant(1.5e-5, 2), TableCell::missing()});
    t.add_row({"10% & $x_1$", TableCell::integer(10800), TableCell::fixed(12.5, 1, "ms")});
    t.add_note("note #1: ~50^2 {ok}");
    return t;
}

std::string read_text(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::vector<std::string> directory_entries(const std::string& dir)
{
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

int run(const std::vector<std::string>& argv, const std::string& out = "", const std::string& err = "")
{
    return lb::run_process(argv, {out.empty() ? "/dev/null" : out, err.empty() ? "/dev/null" : err});
}

const char* const kPython = "/usr/bin/python3";

bool python_has_plotting()
{
    return fs::exists(kPython) &&
           run({kPython, "-c", "import matplotlib, h5py, numpy"}) == 0;
}

} // namespace

TEST(TableCell, Formatting)
{
    EXPECT_EQ(TableCell::fixed(0.72, 3, "ms").text, "0.720 ms");
    EXPECT_DOUBLE_EQ(*TableCell::fixed(0.72, 3, "ms").value, 0.72);
    EXPECT_EQ(TableCell::fixed(268.0, 0).text, "268");
    EXPECT_EQ(TableCell::significant(0.0012345, 3).text, "0.00123");
    EXPECT_EQ(TableCell::integer(10800).text, "10,800");
    EXPECT_EQ(TableCell::integer(576).text, "576");
    EXPECT_EQ(TableCell::integer(-1234567).text, "-1,234,567");
    EXPECT_EQ(TableCell::integer(100000, "frames").text, "100,000 frames");
    EXPECT_EQ(TableCell::fixed(std::nan(""), 2).text, "NaN");
    EXPECT_TRUE(std::isnan(*TableCell::missing().value));
    EXPECT_FALSE(TableCell("text").value.has_value());
}

TEST(Table, RowMustMatchColumns)
{
    Table t;
    t.title = "T";
    t.columns = {"a", "b"};
    EXPECT_THROW(t.add_row({"only one"}), lb::Error);
    t.rows.push_back({"x"});  // bypassing add_row is caught by the writers
    EXPECT_THROW(lb::to_markdown(t), lb::Error);
    EXPECT_THROW(lb::to_csv(t), lb::Error);
    EXPECT_THROW(lb::to_latex(t), lb::Error);
}

TEST(Table, NumericColumns)
{
    const Table t = demo_table();
    EXPECT_FALSE(t.is_numeric_column(0));
    EXPECT_TRUE(t.is_numeric_column(1));
    EXPECT_TRUE(t.is_numeric_column(2));  // a missing cell keeps the column numeric
}

TEST(Table, Markdown)
{
    const std::string expected =
        "## Demo table\n"
        "\n"
        "A small example.\n"
        "\n"
        "| method      |    rmse |     time |\n"
        "|:------------|--------:|---------:|\n"
        "| ours        |   0.123 | 0.720 ms |\n"
        "| a\\|b, \"c\"   | 1.5e-05 |        — |\n"
        "| 10% & $x_1$ |  10,800 |  12.5 ms |\n"
        "\n"
        "- note #1: ~50^2 {ok}\n";
    EXPECT_EQ(lb::to_markdown(demo_table()), expected);
}

TEST(Table, Csv)
{
    // Numeric cells write their exact value; text with ',', '"' or '#' is quoted, '"' doubled.
    const std::string expected =
        "# Demo table\n"
        "# A small example.\n"
        "# note #1: ~50^2 {ok}\n"
        "method,rmse,time\n"
        "ours,0.12345,0.72\n"
        "\"a|b, \"\"c\"\"\",1.5e-05,nan\n"
        "10% & $x_1$,10800,12.5\n";
    EXPECT_EQ(lb::to_csv(demo_table()), expected);

    Table t;
    t.columns = {"#id", "text"};
    t.add_row({"1", " padded"});
    t.add_row({"2", "line\nbreak"});
    EXPECT_EQ(lb::to_csv(t), "\"#id\",text\n1,\" padded\"\n2,\"line\nbreak\"\n");
}

TEST(Table, CsvReadsBackWhatItWrites)
{
    Table t = demo_table();
    t.add_row({"x\ny", TableCell("nan", std::numeric_limits<double>::quiet_NaN()), TableCell("inf", std::numeric_limits<double>::infinity())});
    const Table back = lb::parse_csv(lb::to_csv(t), "demo.csv");
    EXPECT_EQ(back.title, t.title);
    EXPECT_EQ(back.caption, t.caption);
    EXPECT_EQ(back.notes, t.notes);
    EXPECT_EQ(back.columns, t.columns);
    ASSERT_EQ(back.rows.size(), t.rows.size());
    EXPECT_EQ(back.rows[1][0].text, "a|b, \"c\"");
    EXPECT_FALSE(back.rows[1][0].value);
    EXPECT_EQ(*back.rows[0][1].value, 0.12345);  // the value at full precision, not the text "0.123"
    EXPECT_EQ(*back.rows[1][1].value, 1.5e-5);
    EXPECT_TRUE(std::isnan(*back.rows[1][2].value));  // TableCell::missing
    EXPECT_EQ(back.rows[3][0].text, "x\ny");
    EXPECT_TRUE(std::isnan(*back.rows[3][1].value));
    EXPECT_TRUE(std::isinf(*back.rows[3][2].value));
    // malformed input names the source and the line
    try {
        lb::parse_csv("# title\na,b\n1,2\n3\n", "bad.csv");
        FAIL() << "a short row was accepted";
    } catch (const lb::IoError& e) {
        EXPECT_EQ(std::string(e.what()), "bad.csv:4: 1 fields where the header has 2");
    }
    EXPECT_THROW(lb::parse_csv("a,b\n\"open,2\n", "bad.csv"), lb::IoError);
    EXPECT_THROW(lb::parse_csv("# only a title\n", "bad.csv"), lb::IoError);
    EXPECT_THROW(lb::read_csv(std::string(LB_TEST_TMP_DIR) + "/no_such_table.csv"), lb::IoError);
}

TEST(Table, Latex)
{
    const std::string expected =
        "% Demo table (generated by latentbench; needs \\usepackage{booktabs})\n"
        "\\begin{table}[htbp]\n"
        "  \\centering\n"
        "  \\caption{\\textbf{Demo table.} A small example.}\n"
        "  \\label{tab:demo}\n"
        "  \\begin{tabular}{lrr}\n"
        "    \\toprule\n"
        "    method & rmse & time \\\\\n"
        "    \\midrule\n"
        "    ours & 0.123 & 0.720 ms \\\\\n"
        "    a\\textbar{}b, \"c\" & 1.5e-05 & — \\\\\n"
        "    10\\% \\& \\$x\\_1\\$ & 10,800 & 12.5 ms \\\\\n"
        "    \\bottomrule\n"
        "  \\end{tabular}\n"
        "  \\par\\smallskip\n"
        "  {\\footnotesize\n"
        "  note \\#1: \\textasciitilde{}50\\textasciicircum{}2 \\{ok\\}\\par\n"
        "  }\n"
        "\\end{table}\n";
    EXPECT_EQ(lb::to_latex(demo_table()), expected);
    EXPECT_EQ(lb::latex_escape("a\\b<c>"), "a\\textbackslash{}b\\textless{}c\\textgreater{}");
}

TEST(Table, WritesAtomically)
{
    const std::string dir = lb::testing::fresh_dir("table_atomic");
    const Table t = demo_table();
    const auto paths = lb::write_table_files(t, dir + "/demo");
    ASSERT_EQ(paths.size(), 3u);
    EXPECT_EQ(read_text(dir + "/demo.md"), lb::to_markdown(t));
    EXPECT_EQ(read_text(dir + "/demo.csv"), lb::to_csv(t));
    EXPECT_EQ(read_text(dir + "/demo.tex"), lb::to_latex(t));
    // Nothing but the three outputs: no temporary file left behind.
    EXPECT_EQ(directory_entries(dir), (std::vector<std::string>{"demo.csv", "demo.md", "demo.tex"}));

    // Overwriting replaces the whole file.
    Table small;
    small.columns = {"x"};
    small.add_row({TableCell::integer(1)});
    lb::write_csv(small, dir + "/demo.csv");
    EXPECT_EQ(read_text(dir + "/demo.csv"), "x\n1\n");

    // Missing parent directories are created.
    lb::write_markdown(small, dir + "/sub/dir/t.md");
    EXPECT_TRUE(fs::exists(dir + "/sub/dir/t.md"));

    // A path that cannot be written (its "directory" is a file) throws and leaves nothing.
    EXPECT_THROW(lb::write_latex(small, dir + "/demo.md/t.tex"), lb::IoError);
    EXPECT_EQ(directory_entries(dir), (std::vector<std::string>{"demo.csv", "demo.md", "demo.tex", "sub"}));
}

TEST(Table, Provenance)
{
    const std::string machine = lb::machine_description();
    EXPECT_NE(machine.find("logical cores"), std::string::npos) << machine;

    Table t = demo_table();
    t.add_provenance();
    ASSERT_EQ(t.notes.size(), 2u);
    const std::string& note = t.notes.back();
    EXPECT_NE(note.find("machine: " + machine), std::string::npos) << note;
    EXPECT_NE(note.find("threads: " + std::to_string(lb::num_threads())), std::string::npos) << note;
    EXPECT_NE(note.find(std::string("build: ") + LB_BUILD_TYPE), std::string::npos) << note;
    EXPECT_TRUE(std::regex_search(note, std::regex("date: \\d{4}-\\d{2}-\\d{2} \\d{2}:\\d{2} UTC"))) << note;
    // The note reaches every format.
    EXPECT_NE(lb::to_markdown(t).find("- machine: "), std::string::npos);
    EXPECT_NE(lb::to_csv(t).find("# machine: "), std::string::npos);
    EXPECT_NE(lb::to_latex(t).find("machine: "), std::string::npos);
}

TEST(PaperNumbers, Tables)
{
    // Quoted from Li et al. 2025, Tables 1 and 2.
    ASSERT_EQ(lb::paper_table1_rows().size(), 5u);
    ASSERT_EQ(lb::paper_table2_rows().size(), 5u);
    const lb::PaperTable1Row* armadillo = lb::find_paper_table1_row("armadillo");
    ASSERT_NE(armadillo, nullptr);
    EXPECT_EQ(armadillo->full_dofs, 10020);
    EXPECT_EQ(armadillo->subspace_dofs, 12);
    EXPECT_DOUBLE_EQ(armadillo->simulation_ms, 136.8);
    EXPECT_DOUBLE_EQ(armadillo->total_ms, 0.489);
    EXPECT_EQ(lb::find_paper_table1_row("cantilever"), nullptr);
    for (const auto& r1 : lb::paper_table1_rows()) {
        // The printed totals are integration + decoder, and Table 2's "Ours" is Table 1's total.
        EXPECT_NEAR(r1.integration_ms + r1.decoder_ms, r1.total_ms, 1e-9) << r1.scene;
        const lb::PaperTable2Row* r2 = lb::find_paper_table2_row(r1.scene);
        ASSERT_NE(r2, nullptr) << r1.scene;
        EXPECT_DOUBLE_EQ(r2->ours_ms, r1.total_ms) << r1.scene;
        EXPECT_EQ(r2->full_dofs, r1.full_dofs) << r1.scene;
        EXPECT_EQ(r2->subspace_dofs, r1.subspace_dofs) << r1.scene;
    }
    EXPECT_EQ(lb::format_layers(lb::find_paper_table2_row("rods_rotate")->decoder_layers), "512, 512, 512, 50");
    EXPECT_EQ(lb::format_layers(lb::find_paper_table2_row("cloth")->integrator_layers), "32, 32");

    // Rendered as printed in the paper.
    const std::string md1 = lb::to_markdown(lb::paper_table1());
    EXPECT_NE(md1.find("| Hair Rotation    | rods_rotate    |   10,800 |"), std::string::npos) << md1;
    for (const char* printed : {"268 ms", "18.83 ms", "136.8 ms", "0.720 ms", "0.489 ms"}) {
        EXPECT_NE(md1.find(printed), std::string::npos) << printed << "\n" << md1;
    }
    const std::string md2 = lb::to_markdown(lb::paper_table2());
    for (const char* printed : {"2.19 ms", "0.564 ms", "256, 256, 256, 256, 256"}) {
        EXPECT_NE(md2.find(printed), std::string::npos) << printed << "\n" << md2;
    }
}

// ---- scripts/plot_rollouts.py on a rollout file in `latentbench rollout`'s layout ----

namespace {

/// Two methods on one sequence plus one on a second sequence; 40 frames each.
void write_fake_rollouts(const std::string& path)
{
    const auto& columns = lb::metric_column_names();
    std::string joined;
    for (const auto& c : columns) joined += (joined.empty() ? "" : ",") + c;
    const int frames = 40;
    struct Spec {
        const char* method;
        const char* sequence;
        double growth;
        int stable;
    };
    const Spec specs[] = {{"ours", "corners_line", 0.01, frames},
                          {"supervised_l2", "corners_line", 0.2, 25},
                          {"ours", "second", 0.02, frames}};
    lb::h5::File f = lb::h5::File::create(path);
    f.set_attribute("/", "config", std::string("fake rollouts for test_table"));
    f.set_attribute("/", "num_rollouts", (long long)std::size(specs));
    f.set_attribute("/", "metric_columns", joined);
    for (size_t k = 0; k < std::size(specs); ++k) {
        const Spec& s = specs[k];
        lb::MatrixXd m = lb::MatrixXd::Zero(frames, lb::kNumMetricColumns);
        for (int t = 2; t < frames; ++t) {
            m(t, lb::kRmse) = 1e-3 * std::exp(s.growth * t);
            m(t, lb::kBcViolation) = 1e-5 * t;
            m(t, lb::kKinetic) = 0.8 * (1.0 + std::sin(0.3 * t));
            m(t, lb::kKineticGt) = 1.0 + std::sin(0.3 * t);
            m(t, lb::kKineticFree) = 0.1 * m(t, lb::kKinetic);
            m(t, lb::kKineticFreeGt) = 0.1 * m(t, lb::kKineticGt);
            m(t, lb::kElastic) = m(t, lb::kElasticGt) = 0.1;
        }
        if (s.stable < frames) m.bottomRows(5).setConstant(std::nan(""));  // a diverged tail
        const std::string g = "rollouts/" + std::to_string(k);
        f.write(g + "/metrics", m);
        f.set_attribute(g, "method", std::string(s.method));
        f.set_attribute(g, "sequence", std::string(s.sequence));
        f.set_attribute(g, "frames", (long long)frames);
        f.set_attribute(g, "stable_horizon", (long long)s.stable);
        f.set_attribute(g, "ke_ratio", 0.8);
    }
}

} // namespace

TEST(PlotScripts, PlotRolloutsWritesPngs)
{
    if (!python_has_plotting()) GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib/h5py/numpy";
    const std::string dir = lb::testing::fresh_dir("plot_rollouts");
    const std::string rollouts = dir + "/rollouts.h5";
    write_fake_rollouts(rollouts);
    const std::string script = std::string(LB_SOURCE_DIR) + "/scripts/plot_rollouts.py";
    const std::string out = dir + "/figures";
    const int code = run({kPython, script, rollouts, "-o", out, "--title", "test", "--train-frames", "20"},
                         dir + "/stdout.txt", dir + "/stderr.txt");
    ASSERT_EQ(code, 0) << read_text(dir + "/stderr.txt");
    const std::string printed = read_text(dir + "/stdout.txt");
    for (const char* sequence : {"corners_line", "second"}) {
        for (const char* metric : {"rmse", "bc_violation", "kinetic", "kinetic_free"}) {
            const std::string png = out + "/" + sequence + "_" + metric + ".png";
            ASSERT_TRUE(fs::exists(png)) << png;
            EXPECT_GT(fs::file_size(png), 1000u) << png;
            EXPECT_EQ(read_text(png).substr(1, 3), "PNG") << png;
            EXPECT_NE(printed.find(png), std::string::npos) << printed;
        }
    }
    EXPECT_EQ(directory_entries(out).size(), 8u);  // no temporary files left
}

TEST(PlotScripts, PlotRolloutsRejectsMissingAndCorruptFiles)
{
    if (!python_has_plotting()) GTEST_SKIP() << "/usr/bin/python3 lacks matplotlib/h5py/numpy";
    const std::string dir = lb::testing::fresh_dir("plot_rollouts_bad");
    const std::string script = std::string(LB_SOURCE_DIR) + "/scripts/plot_rollouts.py";
    lb::testing::write_file(dir + "/corrupt.h5", "not an HDF5 file");
    for (const std::string& input : {dir + "/missing.h5", dir + "/corrupt.h5"}) {
        const int code = run({kPython, script, input, "-o", dir + "/figures"}, "", dir + "/stderr.txt");
        EXPECT_EQ(code, 1) << input;
        const std::string err = read_text(dir + "/stderr.txt");
        EXPECT_NE(err.find("plot_rollouts.py: error:"), std::string::npos) << err;
        EXPECT_NE(err.find(input), std::string::npos) << err;
        EXPECT_EQ(err.find("Traceback"), std::string::npos) << err;
    }
    EXPECT_FALSE(fs::exists(dir + "/figures"));
}
