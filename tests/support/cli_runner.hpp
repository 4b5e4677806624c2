#pragma once
// Run the latentbench CLI from a test and capture its exit code and output.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace lb::testing {

struct CliResult {
    int exit_code = -1;
    std::string output;  ///< stdout and stderr together
};

inline CliResult run_cli(const std::string& args)
{
    const std::string log = std::string(LB_TEST_TMP_DIR) + "/cli_output_" + std::to_string(::getpid()) + ".txt";
    const std::string cmd = std::string(LB_CLI_PATH) + " " + args + " > " + log + " 2>&1";
    const int status = std::system(cmd.c_str());
    CliResult result;
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(log);
    std::ostringstream ss;
    ss << in.rdbuf();
    result.output = ss.str();
    std::filesystem::remove(log);
    return result;
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

} // namespace lb::testing
