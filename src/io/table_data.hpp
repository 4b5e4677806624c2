#pragma once
// A table's structured twin: `<stem>.table.toml` beside `<stem>.md/.csv/.tex`, holding
// exactly what a Table holds (title, caption, label, columns, notes, and per cell its
// text and, if any, its numeric value). The Markdown shows only the text and the CSV
// only the value of a numeric cell; this file keeps both, so a later reader (the suite
// page, pipeline/html_page.hpp) rebuilds the same Table instead of parsing either.
#include <string>

#include "io/table.hpp"

namespace lb {

/// The TOML text of a table: top-level title, caption, label, columns, notes, and
/// `rows`, an array of rows, each an array of cells {text = "...", value = 1.5} (value
/// absent for a text cell; nan and inf as TOML spells them).
std::string to_table_toml(const Table& table);
/// Parse to_table_toml's text; IoError naming `source` if a key is missing or has the
/// wrong type, or a row's cell count differs from the columns'.
Table parse_table_toml(const std::string& text, const std::string& source);
/// Write `<stem>.table.toml` atomically; returns its path.
std::string write_table_data(const Table& table, const std::string& stem);
/// parse_table_toml of a file; IoError naming the path if it cannot be read.
Table read_table_data(const std::string& path);

} // namespace lb
