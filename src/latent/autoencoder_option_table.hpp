#pragma once
// The numeric options of the autoencoder's training in one table: each option's suite
// key ([autoencoder], [scenes.autoencoder]), its `train-ae` flag and its range. The suite
// reader (pipeline/experiment_config.cpp) and the command line (cli/cmd_train_ae.cpp)
// both check values against this table, so a value refused in one is refused in the
// other, with the same range in the message.
#include <string>
#include <vector>

namespace lb {

struct AutoencoderOptionSpec {
    const char* key;   ///< suite key (nullptr: command line only)
    const char* flag;  ///< `train-ae` flag (nullptr: suite only)
    bool integer;      ///< integer (range [int_min, int_max]) or real (range from min, max)
    long long int_min = 0, int_max = 0;
    double min = 0.0, max = 0.0;  ///< real: finite values in this range, ends open as below
    bool min_open = false, max_open = false;

    /// "[1, 10000000]", "(0, 1)", "(0, ∞)".
    std::string range_text() const;
    /// "" if `value` is in range, else "must lie in <range>, got <value>".
    std::string problem(long long value) const;
    std::string problem(double value) const;
    /// The text of a command-line value: "" if it parses (a whole integer for an integer
    /// option, a number otherwise) and lies in range, else what is wrong.
    std::string text_problem(const std::string& text) const;
};

/// Every option, in the order of `train-ae --help`.
const std::vector<AutoencoderOptionSpec>& autoencoder_option_table();
/// The option with this suite key; std::logic_error if none (a programming error).
const AutoencoderOptionSpec& autoencoder_option_by_key(const std::string& key);
/// The option with this flag (e.g. "--validation"); std::logic_error if none.
const AutoencoderOptionSpec& autoencoder_option_by_flag(const std::string& flag);

} // namespace lb
