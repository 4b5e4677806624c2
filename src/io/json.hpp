#pragma once
// A minimal JSON reader (objects, arrays, strings, numbers, true/false/null) for the
// small documents latentbench reads: network architectures (nn/architecture.hpp) and a
// run's provenance.json (pipeline/report.hpp). Bounded in size and nesting depth, so a
// hostile document cannot exhaust memory or the stack; every error is an IoError that
// names the document (`what`) and the offset.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace lb {

struct JsonValue {
    enum class Type { null, boolean, number, string, array, object } type = Type::null;
    bool b = false;
    double num = 0.0;
    std::string str;
    std::vector<JsonValue> arr;
    std::map<std::string, JsonValue> obj;
    std::string what;  ///< the document's name, for errors ("architecture", a file path)

    /// The member `key` of an object; IoError "<what>: missing key '<key>'" otherwise.
    const JsonValue& at(const std::string& key) const;
    bool has(const std::string& key) const { return type == Type::object && obj.count(key) > 0; }
    /// IoError "<what>: expected a number/string" if of another type.
    double number() const;
    const std::string& string() const;
};

/// `text` as a JSON string literal, quotes included: '"' and '\\' escaped, control
/// characters as \u00XX (what parse_json reads back).
std::string json_quote(const std::string& text);

/// Parse `text`; IoError "<what>: malformed JSON (...) at offset N" on a syntax error, a
/// document longer than `max_bytes` or nested deeper than `max_depth`. Strings take the
/// escapes \n \t \r \b \f \" \\ \/ and \u00XX (ASCII).
JsonValue parse_json(const std::string& text, const std::string& what, std::size_t max_bytes, int max_depth);

} // namespace lb
