#pragma once
// What built this binary and how it was invoked, for the provenance every table and
// results folder records: the git commit of the sources at build time (with a dirty flag
// for uncommitted changes to tracked files) and the command line of this process.
#include <string>
#include <vector>

namespace lb {

/// The 40-hex commit the binary was built from, or "unknown" (no git, not a checkout).
/// Defined in the build's generated/build_info.cpp (cmake/build_info.cmake).
const char* build_commit();
/// True if tracked files differed from build_commit() when the binary was built.
bool build_dirty();
/// "434ffe6a1b2c" or "434ffe6a1b2c+dirty" (12 hex digits), or "unknown".
std::string build_commit_short();

/// Record this process's command line (main() calls it once); argv[0] is reduced to its file
/// name so that no absolute install path is recorded.
void set_command_line(int argc, const char* const* argv);
/// The recorded arguments (empty if set_command_line was never called, e.g. in tests).
const std::vector<std::string>& command_line();
/// The command line as one line, each argument quoted if it holds a space or a quote.
std::string command_line_text();

} // namespace lb
