#pragma once
// One static web page per suite (`index.html` in the suite's folder): per scene the
// methods table (sortable by any column, diverged cells marked, seeds per method), the
// error decomposition, embedding and deviations tables, the filmstrip, the video, the
// per-metric plots and the training curves; the paper's Tables 1 and 2; the provenance
// (the run's provenance.json).
// Self-contained: inline style and a few lines of inline script, no network; figures and
// videos by relative path. Everything shown is HTML-escaped.
//
// The page is built from a folder, not from memory, so a run and a later rebuild
// (`latentbench page`) take the same path: each table from its structured twin
// `<stem>.table.toml` (io/table_data.hpp; the same Table the Markdown and CSV were
// written from). A folder published before those twins existed (results/) has only the
// CSV: its tables are read from it and the page says, at the top and under each table,
// that the CSV keeps numbers but not the Markdown's cell texts (diverged markers,
// budgets), so those cells cannot be marked there.
#include <string>
#include <vector>

namespace lb {

/// Write `<dir>/index.html` (atomically) for a suite folder: a run's output folder or a
/// published results/ folder (tables in `<dir>/tables/` or in `<dir>` itself). Returns
/// its path. IoError naming the folder if it holds no methods table.
std::string write_suite_page(const std::string& dir);

/// Write a page at `path` listing the suites in `suite_dirs` (name, description, scenes,
/// a relative link to each one's index.html). IoError naming a folder without index.html.
std::string write_suite_listing(const std::vector<std::string>& suite_dirs, const std::string& path);

} // namespace lb
