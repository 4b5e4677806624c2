// The structured twin of a table (io/table_data.hpp): every cell's text and value survive
// a round trip exactly, including numbers the Markdown and CSV would each show only half of;
// malformed files are refused with the file named.
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "io/table_data.hpp"
#include "support/cli_runner.hpp"

namespace {

using lb::Table;
using lb::TableCell;

Table sample()
{
    Table t;
    t.title = "Methods on \"cloth\" <small>";
    t.caption = "A caption with 'quotes', a backslash \\ and a line\nbreak; unicode: ≥ µ —";
    t.label = "tab:x";
    t.columns = {"method", "stable (blow-up)", "mean RMSE", "empty"};
    t.add_row({"ours", TableCell("diverged @12", 12.0), TableCell("0.0123 (diverged @12)", 0.012345678901234567),
               TableCell()});
    t.add_row({"pca", TableCell("50 / 50", 50.0), TableCell::missing("nan"), TableCell("inf", std::numeric_limits<double>::infinity())});
    t.add_row({"x", TableCell("tiny", 1e-300), TableCell("neg", -0.1), TableCell("big", 1.7976931348623157e308)});
    t.add_note("training horizon: 100 frames");
    t.add_note("machine: test");
    return t;
}

TEST(TableData, RoundTripKeepsEveryTextAndValueExactly)
{
    const Table a = sample();
    const Table b = lb::parse_table_toml(lb::to_table_toml(a), "mem");
    EXPECT_EQ(b.title, a.title);
    EXPECT_EQ(b.caption, a.caption);
    EXPECT_EQ(b.label, a.label);
    EXPECT_EQ(b.columns, a.columns);
    EXPECT_EQ(b.notes, a.notes);
    ASSERT_EQ(b.rows.size(), a.rows.size());
    for (size_t r = 0; r < a.rows.size(); ++r) {
        for (size_t c = 0; c < a.columns.size(); ++c) {
            const TableCell& x = a.rows[r][c];
            const TableCell& y = b.rows[r][c];
            EXPECT_EQ(y.text, x.text) << r << "," << c;
            ASSERT_EQ(y.value.has_value(), x.value.has_value()) << r << "," << c;
            if (!x.value) continue;
            if (std::isnan(*x.value)) EXPECT_TRUE(std::isnan(*y.value)) << r << "," << c;
            else EXPECT_EQ(*y.value, *x.value) << r << "," << c;  // bit-exact, not approximately
        }
    }
    // The Markdown and the CSV each lose half of such a cell; the twin keeps both.
    EXPECT_EQ(b.rows[0][2].text, "0.0123 (diverged @12)");
    EXPECT_EQ(*b.rows[0][2].value, 0.012345678901234567);
}

TEST(TableData, WritesAndReadsAFile)
{
    const std::string dir = lb::testing::fresh_dir("table_data");
    const std::string path = lb::write_table_data(sample(), dir + "/methods_cloth");
    EXPECT_EQ(path, dir + "/methods_cloth.table.toml");
    EXPECT_EQ(lb::read_table_data(path).rows.size(), 3u);
    // atomic: nothing but the file itself
    size_t entries = 0;
    for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++entries;
    EXPECT_EQ(entries, 1u);
}

TEST(TableData, RefusesMalformedFilesNamingThem)
{
    const std::string good = lb::to_table_toml(sample());
    auto message = [](const std::string& text) {
        try {
            lb::parse_table_toml(text, "bad.table.toml");
        } catch (const lb::IoError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("title = [").find("bad.table.toml"), std::string::npos);
    EXPECT_NE(message("caption = \"c\"\nlabel = \"\"\ncolumns = []\nnotes = []\nrows = []").find("'title'"), std::string::npos);
    // a row with too few cells
    std::string short_row = "title = \"t\"\ncaption = \"\"\nlabel = \"\"\ncolumns = [\"a\", \"b\"]\nnotes = []\n"
                            "rows = [[{text = \"x\"}]]\n";
    const std::string m = message(short_row);
    EXPECT_NE(m.find("row 1 has 1 cells for 2 columns"), std::string::npos) << m;
    EXPECT_NE(m.find("bad.table.toml"), std::string::npos) << m;
    EXPECT_NE(message("title = \"t\"\ncaption = \"\"\nlabel = \"\"\ncolumns = [\"a\"]\nnotes = []\n"
                      "rows = [[{text = \"x\", value = \"1\"}]]\n").find("not a number"),
              std::string::npos);
    EXPECT_EQ(message(good), "no error");
    EXPECT_THROW(lb::read_table_data("/nonexistent/x.table.toml"), lb::Error);
}

} // namespace
