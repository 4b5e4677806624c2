// One range per option (issue 44, item 4): an autoencoder option that exists both as a
// `train-ae` flag and as a suite key takes its range from latent/autoencoder_option_table:
// a value outside it is refused by both, each message naming the flag or key and the
// same range. `train-ae --validation -5` used to be accepted (no validation at all) while
// the suite key `validation` was checked against (0, 1).
#include "lb_paths.hpp"
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <string>

#include "latent/autoencoder_option_table.hpp"
#include "support/cli_runner.hpp"

namespace lb {
namespace {

using testing::fresh_dir;
using testing::run_cli;
using testing::write_file;

/// A value just outside the option's range (below its lower end), as TOML and CLI text.
std::string below_range(const AutoencoderOptionSpec& spec)
{
    if (spec.integer) return std::to_string(spec.int_min - 1);
    std::ostringstream os;
    os.precision(17);
    os << std::showpoint << (spec.min_open ? spec.min : spec.min - 1.0);
    return os.str();
}

/// A value just outside the option's range (above its upper end); empty if unbounded.
std::string above_range(const AutoencoderOptionSpec& spec)
{
    if (spec.integer) return spec.int_max < std::numeric_limits<long long>::max() ? std::to_string(spec.int_max + 1) : "";
    if (std::isinf(spec.max)) return "";
    std::ostringstream os;
    os.precision(17);
    os << std::showpoint << (spec.max_open ? spec.max : spec.max + 1.0);
    return os.str();
}

void expect_refused(const std::string& args, const std::string& name, const std::string& range)
{
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.output;
    const size_t at = r.output.find("latentbench: error:");
    ASSERT_NE(at, std::string::npos) << args << "\n" << r.output;
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    EXPECT_NE(line.find(name), std::string::npos) << args << "\n" << line;
    EXPECT_NE(line.find(range), std::string::npos) << args << "\n" << line;
}

TEST(CliOptionRanges, FlagAndSuiteKeyRefuseTheSameValues)
{
    const std::string dir = fresh_dir("cli_option_ranges");
    const std::string suite_head = "name = \"x\"\n[[integrators]]\nname = \"pca\"\nmethod = \"linear_pca\"\n"
                                   "[[scenes]]\nscene = \"" + std::string(LB_SOURCE_DIR) +
                                   "/experiments/scenes/cantilever.toml\"\nvariant = \"small\"\n[autoencoder]\n";
    int both = 0;
    for (const AutoencoderOptionSpec& spec : autoencoder_option_table()) {
        if (!spec.key || !spec.flag) continue;
        ++both;
        for (const std::string& value : {below_range(spec), above_range(spec)}) {
            if (value.empty()) continue;
            SCOPED_TRACE(std::string(spec.key) + " = " + value);
            expect_refused("train-ae " + dir + "/data.h5 -o " + dir + "/ae.h5 " + spec.flag + "=" + value, spec.flag,
                           spec.range_text());
            write_file(dir + "/suite.toml", suite_head + spec.key + " = " + value + "\n");
            expect_refused("run " + dir + "/suite.toml -o " + dir + "/run --check", std::string("'autoencoder.") + spec.key + "'",
                           spec.range_text());
        }
    }
    EXPECT_GE(both, 10);
    // The case, spelled out.
    expect_refused("train-ae " + dir + "/data.h5 -o " + dir + "/ae.h5 --validation -5", "--validation", "(0, 1)");
    write_file(dir + "/suite.toml", suite_head + "validation = -5.0\n");
    expect_refused("run " + dir + "/suite.toml -o " + dir + "/run --check", "validation", "(0, 1)");
}

TEST(AutoencoderOptionTable, RangesAndMessages)
{
    const AutoencoderOptionSpec& validation = autoencoder_option_by_key("validation");
    EXPECT_EQ(&validation, &autoencoder_option_by_flag("--validation"));
    EXPECT_EQ(validation.range_text(), "(0, 1)");
    EXPECT_EQ(validation.problem(0.5), "");
    EXPECT_NE(validation.problem(0.0), "");
    EXPECT_NE(validation.problem(1.0), "");
    EXPECT_NE(validation.problem(std::nan("")), "");
    EXPECT_NE(validation.text_problem("-5").find("got -5"), std::string::npos);
    EXPECT_NE(validation.text_problem("abc"), "");
    const AutoencoderOptionSpec& epochs = autoencoder_option_by_key("epochs");
    EXPECT_EQ(epochs.problem(1LL), "");
    EXPECT_NE(epochs.problem(0LL).find("[1, "), std::string::npos);
    EXPECT_NE(epochs.text_problem("2.5"), "");
    EXPECT_EQ(autoencoder_option_by_key("physics_weight").problem(0.0), "");
    EXPECT_NE(autoencoder_option_by_key("learning_rate").problem(0.0), "");
    EXPECT_NE(autoencoder_option_by_key("learning_rate").problem(std::numeric_limits<double>::infinity()), "");
}

} // namespace
} // namespace lb
