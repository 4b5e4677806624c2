#include "latent/autoencoder_option_table.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/limits.hpp"

namespace lb {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

AutoencoderOptionSpec integer_option(const char* key, const char* flag, long long min, long long max)
{
    AutoencoderOptionSpec s{key, flag, true};
    s.int_min = min;
    s.int_max = max;
    return s;
}

AutoencoderOptionSpec real_option(const char* key, const char* flag, double min, bool min_open, double max, bool max_open)
{
    AutoencoderOptionSpec s{key, flag, false};
    s.min = min;
    s.max = max;
    s.min_open = min_open;
    s.max_open = max_open;
    return s;
}

std::string number_text(double x)
{
    if (std::isinf(x)) return x > 0 ? "∞" : "-∞";
    std::ostringstream os;
    os << x;
    return os.str();
}

} // namespace

const std::vector<AutoencoderOptionSpec>& autoencoder_option_table()
{
    static const std::vector<AutoencoderOptionSpec> table{
        integer_option("latent", "--latent", 1, kMaxWidth),
        integer_option("epochs", "--epochs", 1, kMaxEpochs),
        integer_option("batch", "--batch", 2, kMaxBatch),  // training-mode BatchNorm needs two frames
        real_option("learning_rate", "--lr", 0.0, true, kInf, true),
        integer_option("pca", "--pca", 0, kMaxWidth),
        integer_option("seed", "--seed", 0, kMaxSeed),
        integer_option(nullptr, "--checkpoint-every", 1, kMaxEpochs),
        integer_option("patience", "--patience", 0, kMaxEpochs),
        real_option("validation", "--validation", 0.0, true, 1.0, true),
        integer_option("physics_epochs", "--physics-epochs", 0, kMaxEpochs),
        real_option("physics_weight", "--physics-weight", 0.0, false, kInf, true),
        real_option("physics_learning_rate", "--physics-lr", 0.0, true, kInf, true),
        integer_option("physics_batch", nullptr, 1, kMaxBatch),
    };
    return table;
}

const AutoencoderOptionSpec& autoencoder_option_by_key(const std::string& key)
{
    for (const AutoencoderOptionSpec& s : autoencoder_option_table())
        if (s.key && key == s.key) return s;
    throw std::logic_error("autoencoder_option_by_key: no option '" + key + "'");
}

const AutoencoderOptionSpec& autoencoder_option_by_flag(const std::string& flag)
{
    for (const AutoencoderOptionSpec& s : autoencoder_option_table())
        if (s.flag && flag == s.flag) return s;
    throw std::logic_error("autoencoder_option_by_flag: no option '" + flag + "'");
}

std::string AutoencoderOptionSpec::range_text() const
{
    if (integer) return "[" + std::to_string(int_min) + ", " + std::to_string(int_max) + "]";
    return (min_open ? "(" : "[") + number_text(min) + ", " + number_text(max) + (max_open ? ")" : "]");
}

std::string AutoencoderOptionSpec::problem(long long value) const
{
    if (!integer) return problem(double(value));
    if (value >= int_min && value <= int_max) return "";
    return "must lie in " + range_text() + ", got " + std::to_string(value);
}

std::string AutoencoderOptionSpec::problem(double value) const
{
    if (integer) {
        if (value != std::floor(value) || !std::isfinite(value))
            return "must be a whole number in " + range_text() + ", got " + number_text(value);
        return problem((long long)value);
    }
    const bool above = min_open ? value > min : value >= min;
    const bool below = max_open ? value < max : value <= max;
    if (std::isfinite(value) && above && below) return "";
    return "must lie in " + range_text() + ", got " + number_text(value);
}

std::string AutoencoderOptionSpec::text_problem(const std::string& text) const
{
    errno = 0;
    char* end = nullptr;
    if (integer) {
        const long long v = std::strtoll(text.c_str(), &end, 10);
        if (text.empty() || *end != '\0' || errno == ERANGE)
            return "must be a whole number in " + range_text() + ", got '" + text + "'";
        return problem(v);
    }
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0') return "must be a number in " + range_text() + ", got '" + text + "'";
    return problem(v);
}

} // namespace lb
