#pragma once
// Run the latentbench CLI (or another program) from a test and capture its exit
// code and output, through an argument vector (core/process.hpp), never a shell.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/process.hpp"

namespace lb::testing {

struct CliResult {
    int exit_code = -1;
    std::string output;  ///< stdout and stderr together
};

/// Run argv (argv[0] an absolute path); stdout and stderr together in the output.
inline CliResult run_program(const std::vector<std::string>& argv)
{
    const std::string log = std::string(LB_TEST_TMP_DIR) + "/cli_output_" + std::to_string(::getpid()) + ".txt";
    std::ofstream(log).close();  // both streams append to it, so they interleave in order
    CliResult result;
    result.exit_code = lb::run_process(argv, {log, log, /*append_stdout=*/true});
    std::ifstream in(log);
    std::ostringstream ss;
    ss << in.rdbuf();
    result.output = ss.str();
    std::filesystem::remove(log);
    return result;
}

/// The CLI with whitespace-separated arguments (test paths contain no spaces).
inline CliResult run_cli(const std::string& args)
{
    std::vector<std::string> argv{LB_CLI_PATH};
    std::istringstream words(args);
    for (std::string w; words >> w;) argv.push_back(w);
    return run_program(argv);
}

/// A fresh, empty directory under the test temp dir.
inline std::string fresh_dir(const std::string& name)
{
    const std::filesystem::path dir = std::filesystem::path(LB_TEST_TMP_DIR) / name;
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    return dir.string();
}

inline void write_file(const std::string& path, const std::string& text)
{
    std::ofstream(path) << text;
}

/// `text` as `file` in the fresh directory `dir` (fresh_dir); returns the file's path.
inline std::string write_in_fresh_dir(const std::string& dir, const std::string& file, const std::string& text)
{
    const std::string path = fresh_dir(dir) + "/" + file;
    write_file(path, text);
    return path;
}

/// Testcases in a JUnit file, counted by Debian's Python (xml.etree), or -1 (with a test
/// failure) if it does not parse.
inline int python_testcases(const std::string& junit)
{
    const std::string out = junit + ".count";
    const auto result = run_program({"/usr/bin/python3", "-c",
                                     "import sys, xml.etree.ElementTree as ET\n"
                                     "root = ET.parse(sys.argv[1]).getroot()\n"
                                     "assert root.tag == 'testsuites', root.tag\n"
                                     "open(sys.argv[2], 'w').write(str(len(list(root.iter('testcase')))))\n",
                                     junit, out});
    if (result.exit_code != 0) {
        ADD_FAILURE() << "python3 could not parse " << junit << ":\n" << result.output;
        return -1;
    }
    std::ifstream in(out);
    int n = -1;
    in >> n;
    return n;
}

} // namespace lb::testing
