#pragma once
// A small result table (title, caption, column headers, rows of cells, notes)
// and its Markdown, CSV and LaTeX (booktabs) writers. Cells are text, plus an
// optional numeric value: Markdown and LaTeX show the text (formatted by the
// TableCell factories), CSV writes the value at full precision when there is
// one so that scripts read exact numbers. Every writer goes through a
// temporary file and a rename, so a failure never leaves a half-written table.
//
// Every table should carry a provenance note (Table::add_provenance): CPU
// model and core count, thread count, build type, date.
#include <optional>
#include <string>
#include <vector>

namespace lb {

struct TableCell {
    std::string text;
    std::optional<double> value;  ///< numeric value behind `text`, if any

    TableCell() = default;
    TableCell(std::string t) : text(std::move(t)) { }  // NOLINT: implicit on purpose
    TableCell(const char* t) : text(t) { }              // NOLINT
    TableCell(std::string t, double v) : text(std::move(t)), value(v) { }

    /// Fixed-point number, e.g. fixed(0.72, 3, "ms") -> "0.720 ms".
    static TableCell fixed(double v, int decimals, const std::string& unit = "");
    /// `digits` significant digits (%g style), e.g. significant(0.0012345, 3) -> "0.00123".
    static TableCell significant(double v, int digits, const std::string& unit = "");
    /// Integer with thousands separators, e.g. integer(10800) -> "10,800".
    static TableCell integer(long long v, const std::string& unit = "");
    /// A number that is not available (e.g. not reported, or the run diverged):
    /// shown as `text`, written to CSV as "nan"; keeps a numeric column numeric.
    static TableCell missing(const std::string& text = "—");
};

struct Table {
    std::string title;
    std::string caption;
    std::string label;  ///< LaTeX \label (optional)
    std::vector<std::string> columns;
    std::vector<std::vector<TableCell>> rows;
    std::vector<std::string> notes;  ///< one line each, printed below the table

    /// Append a row; throws lb::Error if it does not have one cell per column.
    void add_row(std::vector<TableCell> cells);
    void add_note(std::string note) { notes.push_back(std::move(note)); }
    /// Append the provenance note: machine, threads, build type, date. `threads` replaces
    /// this process's thread count where the table's times were measured elsewhere (e.g.
    /// "1 (the processes that timed the rollouts)").
    void add_provenance(const std::string& threads = "");
    /// True if every non-empty cell of column c has a numeric value (right-aligned).
    bool is_numeric_column(size_t c) const;
};

/// "AMD EPYC 7B13 (2 logical cores, x86_64)": CPU model from /proc/cpuinfo
/// ("model name"), logical core count and machine architecture.
std::string machine_description();
/// The current time, "2025-01-31 14:05 UTC".
std::string utc_now();
/// "machine: ...; threads: N; build: Release; commit: 434ffe6a1b2c+dirty; date: 2025-01-31 14:05 UTC"; `threads`, if
/// given, stands for N (this process's thread count).
std::string provenance_note(const std::string& threads = "");

/// GitHub-flavoured Markdown: "## title", caption paragraph, table (numeric
/// columns right-aligned, '|' escaped), notes as a bullet list.
std::string to_markdown(const Table& table);
/// RFC 4180 CSV (header + rows, CRLF-free: '\n' line ends); title, caption and
/// notes as leading "# " comment lines (pandas: read_csv(path, comment='#')).
/// A cell with a numeric value writes the value (shortest exact decimal, "nan",
/// "inf"); fields with ',', '"', '#', line breaks or edge spaces are quoted.
std::string to_csv(const Table& table);
/// Read a table written by to_csv: the leading "# " comment lines become title, caption and
/// notes (in to_csv's order), then the header and the rows. A field that is a whole number in
/// to_csv's spelling ("0.25", "1e-05", "nan", "inf") gets a value; every other field is text.
/// Throws IoError naming `source` and the line if the header is missing, a quoted field is
/// not closed or a row's field count differs from the header's.
Table parse_csv(const std::string& text, const std::string& source);
/// parse_csv of a file; IoError naming the path if it cannot be read.
Table read_csv(const std::string& path);

/// A booktabs `table` float (\toprule/\midrule/\bottomrule) with caption, label
/// and notes in \footnotesize below; LaTeX specials in all text are escaped.
std::string to_latex(const Table& table);

/// Escape & % $ # _ { } ~ ^ \ < > | for LaTeX text mode.
std::string latex_escape(const std::string& text);

/// Atomic writers (temporary file + rename); throw lb::IoError on failure.
void write_markdown(const Table& table, const std::string& path);
void write_csv(const Table& table, const std::string& path);
void write_latex(const Table& table, const std::string& path);
/// Write `<stem>.md`, `<stem>.csv` and `<stem>.tex`; returns the three paths.
std::vector<std::string> write_table_files(const Table& table, const std::string& stem);

} // namespace lb
