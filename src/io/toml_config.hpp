#pragma once
// Validated access to TOML configuration. Every read records the key; after a
// table has been consumed, finish() rejects any key that was never read, so a
// typo is an error naming the key, not a silently ignored setting. Errors
// carry the dotted key path (e.g. "mesh.nx") and the file name.
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "core/limits.hpp"
#include "core/types.hpp"

namespace lb {

class ConfigTable {
public:
    /// @param table   the TOML table (must outlive this object)
    /// @param path    dotted path of this table ("" for the root)
    /// @param source  file name for messages
    ConfigTable(const toml::table& table, std::string path, std::string source);

    bool has(const std::string& key) const;

    double get_double(const std::string& key, double fallback);
    double require_double(const std::string& key);
    /// Integers are range-checked: a value outside [min, max] is a ConfigError naming
    /// the key and the range, so no option wraps when narrowed or asks for an
    /// allocation that cannot succeed. The fallback is returned unchecked.
    long long get_int(const std::string& key, long long fallback, long long min, long long max);
    long long require_int(const std::string& key, long long min, long long max);
    /// get_int narrowed to int (max must fit an int).
    int get_count(const std::string& key, int fallback, int min, int max);
    bool get_bool(const std::string& key, bool fallback);
    std::string get_string(const std::string& key, const std::string& fallback);
    std::string require_string(const std::string& key);
    Vector3d get_vec3(const std::string& key, const Vector3d& fallback);
    Vector3d require_vec3(const std::string& key);
    std::vector<double> get_double_array(const std::string& key, const std::vector<double>& fallback);
    std::vector<long long> get_int_array(const std::string& key, const std::vector<long long>& fallback,
                                         long long min, long long max);
    std::vector<std::string> get_string_array(const std::string& key,
                                              const std::vector<std::string>& fallback);
    /// Layer widths: a non-empty array of integers in [1, kMaxWidth] (fallback if absent).
    std::vector<Index> get_widths(const std::string& key, const std::vector<Index>& fallback);

    /// A sub-table; std::nullopt if absent.
    std::optional<ConfigTable> table(const std::string& key);
    ConfigTable require_table(const std::string& key);
    /// An array of tables ([[key]]); empty if absent.
    std::vector<ConfigTable> table_array(const std::string& key);

    /// Mark a key as known without reading it (e.g. consumed elsewhere).
    void accept(const std::string& key) { m_used.insert(key); }
    /// Mark every key as known: the table is validated by whoever reads it.
    void accept_all();
    /// The sub-table itself (nullptr if absent; ConfigError if not a table), for
    /// merging; its keys are not marked as read.
    const toml::table* raw_table(const std::string& key) const;
    /// Throw ConfigError for the first key that was never read.
    void finish() const;

    /// Full dotted name of a key of this table, for messages.
    std::string key_path(const std::string& key) const;
    [[noreturn]] void fail(const std::string& key, const std::string& message) const;
    const std::string& source() const { return m_source; }

private:
    const toml::node* find(const std::string& key);
    double to_double(const std::string& key, const toml::node& node) const;

    const toml::table* m_table;
    std::string m_path;
    std::string m_source;
    std::set<std::string> m_used;
};

/// Parse TOML text; ConfigError with line and column on a syntax error.
toml::table parse_toml(const std::string& text, const std::string& source);
/// Read and parse a file; ConfigError if missing or malformed.
toml::table parse_toml_file(const std::string& path);
/// Recursively merge `overlay` into `base` (tables merge, everything else replaces).
void merge_toml(toml::table& base, const toml::table& overlay);
/// Serialise a table back to TOML text (the "resolved config" embedded in outputs).
std::string to_toml_string(const toml::table& table);
/// One value as TOML text: a float as the shortest text that reads back as the same
/// double ("0.1", "1.0"), anything else as toml++ prints it.
std::string toml_value_text(const toml::node& value);
/// Read a whole text file; IoError if it cannot be read.
std::string read_text_file(const std::string& path);

} // namespace lb
