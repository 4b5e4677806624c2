// A run directory that is a file: `run`, `plan` and `submit` (with and without --dry-run)
// each exit 1 with one error naming -o (or the suite's output_dir key) and the path, before
// anything is printed or written. `plan` and `submit` used to print the plan and then fail
// on `cannot create '<dir>/manifest.jsonl'`, naming neither -o nor the run directory, and
// `submit --dry-run` printed batch scripts for the file and exited 0.
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "support/cli_runner.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::write_file;
namespace fs = std::filesystem;

std::string suite_text(const std::string& output_dir)
{
    std::string text = "name = \"x\"\n";
    if (!output_dir.empty()) text += "output_dir = \"" + output_dir + "\"\n";
    return text + "[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca\"\n[[scenes]]\nscene = \"" +
           std::string(LB_SOURCE_DIR) + "/experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n";
}

std::string contents(const std::string& path)
{
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

/// `args` exits 1 with exactly one `latentbench: error:` line holding every one of
/// `parts`, prints nothing else (no plan, no scripts) and leaves `file` as it was.
void expect_refused(const std::string& args, const std::vector<std::string>& parts, const std::string& file)
{
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    const size_t at = r.output.find("latentbench: error:");
    ASSERT_NE(at, std::string::npos) << args << ": no error line\n" << r.output;
    EXPECT_EQ(at, 0u) << args << ": printed before the error\n" << r.output;
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    for (const std::string& p : parts) EXPECT_NE(line.find(p), std::string::npos) << "'" << p << "' missing: " << line;
    EXPECT_EQ(line.find("manifest.jsonl"), std::string::npos) << line;
    EXPECT_EQ(line.find("filesystem error"), std::string::npos) << line;
    EXPECT_EQ(contents(file), "not a directory\n") << args;
    EXPECT_TRUE(fs::is_regular_file(file)) << args;
}

TEST(CliRunDirectory, OutputThatIsAFile)
{
    const std::string dir = fresh_dir("cli_run_directory_output");
    write_file(dir + "/suite.toml", suite_text(""));
    const std::string file = dir + "/file";
    write_file(file, "not a directory\n");
    const std::string suite = dir + "/suite.toml";
    for (const std::string command : {"run", "run --check", "plan", "submit", "submit --dry-run"}) {
        expect_refused(command + " " + suite + " -o " + file, {"-o '" + file + "'", "is an existing file", "not a directory"},
                       file);
        // A run directory below the file names the file it would be inside.
        expect_refused(command + " " + suite + " -o " + file + "/run",
                       {"-o '" + file + "/run'", "would be inside '" + file + "', a file"}, file);
    }
    // A directory (created if missing) is still accepted.
    const auto ok = run_cli("plan " + suite + " -o " + dir + "/new/run");
    EXPECT_EQ(ok.exit_code, 0) << ok.output;
    EXPECT_TRUE(fs::is_regular_file(dir + "/new/run/manifest.jsonl"));
    const auto dry = run_cli("submit " + suite + " -o " + dir + "/other --dry-run");
    EXPECT_EQ(dry.exit_code, 0) << dry.output;
    EXPECT_NE(dry.output.find("dry run: nothing written"), std::string::npos) << dry.output;
}

// Without -o the run directory is the suite's output_dir: the error names that key.
TEST(CliRunDirectory, OutputDirKeyThatIsAFile)
{
    const std::string dir = fresh_dir("cli_run_directory_key");
    const std::string file = dir + "/file";
    write_file(file, "not a directory\n");
    write_file(dir + "/suite.toml", suite_text(file));
    for (const std::string command : {"run", "plan", "submit --dry-run"})
        expect_refused(command + " " + dir + "/suite.toml", {"suite.toml", "key 'output_dir'", file}, file);
}

} // namespace
} // namespace lb
