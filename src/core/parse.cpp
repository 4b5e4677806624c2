#include "core/parse.hpp"

#include <cstdlib>
#include <sstream>

namespace lb {

std::optional<std::vector<Index>> parse_positive_list(const std::string& text, Index max)
{
    std::vector<Index> values;
    if (text.empty()) return values;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const long long v = std::strtoll(item.c_str(), &end, 10);
        if (item.empty() || end == item.c_str() || *end != '\0' || v <= 0 || v > max) return std::nullopt;
        values.push_back(static_cast<Index>(v));
    }
    return values;
}

std::string format_list(const std::vector<Index>& values)
{
    std::string s;
    for (size_t i = 0; i < values.size(); ++i) s += (i ? ", " : "") + std::to_string(values[i]);
    return s;
}

} // namespace lb
