#pragma once
// Small text parsers shared by the command line and the file readers.
#include <optional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace lb {

/// "200,200,200" → {200, 200, 200}; "" → {}. std::nullopt if any item is empty, not a
/// whole integer or outside [1, max] (callers raise the error type of their context).
std::optional<std::vector<Index>> parse_positive_list(const std::string& text, Index max);
/// {200, 200, 200} → "200, 200, 200" (tables and keys).
std::string format_list(const std::vector<Index>& values);

} // namespace lb
