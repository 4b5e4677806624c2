#include "io/toml_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/error.hpp"

namespace lb {

ConfigTable::ConfigTable(const toml::table& table, std::string path, std::string source)
    : m_table(&table), m_path(std::move(path)), m_source(std::move(source))
{
}

std::string ConfigTable::key_path(const std::string& key) const
{
    if (key.empty()) return m_path;  // the table itself
    return m_path.empty() ? key : m_path + "." + key;
}

namespace {
size_t edit_distance(const std::string& a, const std::string& b)
{
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
            diagonal = up;
        }
    }
    return row[b.size()];
}
} // namespace

void ConfigTable::fail(const std::string& key, const std::string& message) const
{
    std::string hint;
    if (!m_table->contains(key)) {
        // A required key is missing: point at an unrecognised key that looks like a typo of it.
        for (const auto& [other, node] : *m_table) {
            const std::string k(other.str());
            if (!m_used.count(k) && edit_distance(k, key) <= 2) {
                hint = " (did you mean it instead of the unknown key '" + key_path(k) + "'?)";
            }
        }
    }
    throw ConfigError(m_source + ": key '" + key_path(key) + "': " + message + hint);
}

bool ConfigTable::has(const std::string& key) const { return m_table->contains(key); }

const toml::node* ConfigTable::find(const std::string& key)
{
    m_used.insert(key);
    return m_table->get(key);
}

double ConfigTable::to_double(const std::string& key, const toml::node& node) const
{
    double value;
    if (auto v = node.as_floating_point()) {
        value = v->get();
    } else if (auto i = node.as_integer()) {
        value = double(i->get());
    } else {
        fail(key, "expected a number");
    }
    if (!std::isfinite(value)) fail(key, "must be finite (got " + std::to_string(value) + ")");
    return value;
}

double ConfigTable::get_double(const std::string& key, double fallback)
{
    const toml::node* node = find(key);
    return node ? to_double(key, *node) : fallback;
}

double ConfigTable::require_double(const std::string& key)
{
    const toml::node* node = find(key);
    if (!node) fail(key, "required number is missing");
    return to_double(key, *node);
}

namespace {

std::string range_text(long long min, long long max)
{
    return "[" + std::to_string(min) + ", " + std::to_string(max) + "]";
}

} // namespace

long long ConfigTable::get_int(const std::string& key, long long fallback, long long min, long long max)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    auto i = node->as_integer();
    if (!i) fail(key, "expected an integer");
    const long long v = i->get();
    if (v < min || v > max) fail(key, "must lie in " + range_text(min, max) + ", got " + std::to_string(v));
    return v;
}

long long ConfigTable::require_int(const std::string& key, long long min, long long max)
{
    if (!has(key)) {
        m_used.insert(key);
        fail(key, "required integer is missing");
    }
    return get_int(key, 0, min, max);
}

int ConfigTable::get_count(const std::string& key, int fallback, int min, int max)
{
    return int(get_int(key, fallback, min, max));
}

bool ConfigTable::get_bool(const std::string& key, bool fallback)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    if (auto b = node->as_boolean()) return b->get();
    fail(key, "expected true or false");
}

std::string ConfigTable::get_string(const std::string& key, const std::string& fallback)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    if (auto s = node->as_string()) return s->get();
    fail(key, "expected a string");
}

std::string ConfigTable::require_string(const std::string& key)
{
    if (!has(key)) {
        m_used.insert(key);
        fail(key, "required string is missing");
    }
    return get_string(key, "");
}

std::vector<double> ConfigTable::get_double_array(const std::string& key,
                                                  const std::vector<double>& fallback)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    const toml::array* arr = node->as_array();
    if (!arr) fail(key, "expected an array of numbers");
    std::vector<double> values;
    for (const toml::node& item : *arr) values.push_back(to_double(key, item));
    return values;
}

std::vector<long long> ConfigTable::get_int_array(const std::string& key,
                                                  const std::vector<long long>& fallback, long long min,
                                                  long long max)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    const toml::array* arr = node->as_array();
    if (!arr) fail(key, "expected an array of integers");
    std::vector<long long> values;
    for (const toml::node& item : *arr) {
        auto i = item.as_integer();
        if (!i) fail(key, "expected an array of integers");
        if (i->get() < min || i->get() > max)
            fail(key, "entries must lie in " + range_text(min, max) + ", got " + std::to_string(i->get()));
        values.push_back(i->get());
    }
    return values;
}

std::vector<std::string> ConfigTable::get_string_array(const std::string& key,
                                                       const std::vector<std::string>& fallback)
{
    const toml::node* node = find(key);
    if (!node) return fallback;
    const toml::array* arr = node->as_array();
    if (!arr) fail(key, "expected an array of strings");
    std::vector<std::string> values;
    for (const toml::node& item : *arr) {
        auto s = item.as_string();
        if (!s) fail(key, "expected an array of strings");
        values.push_back(s->get());
    }
    return values;
}

Vector3d ConfigTable::get_vec3(const std::string& key, const Vector3d& fallback)
{
    if (!has(key)) {
        m_used.insert(key);
        return fallback;
    }
    const std::vector<double> v = get_double_array(key, {});
    if (v.size() != 3) fail(key, "expected 3 numbers, got " + std::to_string(v.size()));
    return {v[0], v[1], v[2]};
}

Vector3d ConfigTable::require_vec3(const std::string& key)
{
    if (!has(key)) {
        m_used.insert(key);
        fail(key, "required 3-vector is missing");
    }
    return get_vec3(key, Vector3d::Zero());
}

std::optional<ConfigTable> ConfigTable::table(const std::string& key)
{
    const toml::node* node = find(key);
    if (!node) return std::nullopt;
    const toml::table* t = node->as_table();
    if (!t) fail(key, "expected a table");
    return ConfigTable(*t, key_path(key), m_source);
}

std::vector<Index> ConfigTable::get_widths(const std::string& key, const std::vector<Index>& fallback)
{
    if (!has(key)) {
        m_used.insert(key);
        return fallback;
    }
    const std::vector<long long> w = get_int_array(key, {}, 1, kMaxWidth);
    if (w.empty()) fail(key, "needs at least one width");
    return std::vector<Index>(w.begin(), w.end());
}

void ConfigTable::accept_all()
{
    for (const auto& [key, node] : *m_table) m_used.insert(std::string(key.str()));
}

const toml::table* ConfigTable::raw_table(const std::string& key) const
{
    const toml::node* node = m_table->get(key);
    if (!node) return nullptr;
    if (!node->as_table()) fail(key, "expected a table");
    return node->as_table();
}

ConfigTable ConfigTable::require_table(const std::string& key)
{
    auto t = table(key);
    if (!t) fail(key, "required table is missing");
    return *t;
}

std::vector<ConfigTable> ConfigTable::table_array(const std::string& key)
{
    const toml::node* node = find(key);
    std::vector<ConfigTable> tables;
    if (!node) return tables;
    const toml::array* arr = node->as_array();
    if (!arr) fail(key, "expected an array of tables ([[" + key_path(key) + "]])");
    int i = 0;
    for (const toml::node& item : *arr) {
        const toml::table* t = item.as_table();
        if (!t) fail(key, "expected an array of tables");
        tables.emplace_back(*t, key_path(key) + "[" + std::to_string(i++) + "]", m_source);
    }
    return tables;
}

void ConfigTable::finish() const
{
    for (const auto& [key, node] : *m_table) {
        const std::string k(key.str());
        if (!m_used.count(k)) {
            throw ConfigError(m_source + ": unknown key '" + key_path(k) + "'" +
                              (node.source().begin.line > 0
                                   ? " (line " + std::to_string(node.source().begin.line) + ")"
                                   : std::string()));
        }
    }
}

toml::table parse_toml(const std::string& text, const std::string& source)
{
    try {
        return toml::parse(text, source);
    } catch (const toml::parse_error& e) {
        std::ostringstream msg;
        msg << source << ":" << e.source().begin.line << ":" << e.source().begin.column
            << ": malformed TOML: " << e.description();
        throw ConfigError(msg.str());
    }
}

std::string read_text_file(const std::string& path)
{
    std::ifstream in(path);
    if (!in) throw IoError("cannot read file '" + path + "'");
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

toml::table parse_toml_file(const std::string& path)
{
    std::ifstream probe(path);
    if (!probe) throw ConfigError("config file '" + path + "' does not exist or cannot be read");
    return parse_toml(read_text_file(path), path);
}

void merge_toml(toml::table& base, const toml::table& overlay)
{
    for (const auto& [key, node] : overlay) {
        toml::node* existing = base.get(key);
        if (existing && existing->is_table() && node.is_table()) {
            merge_toml(*existing->as_table(), *node.as_table());
        } else {
            base.insert_or_assign(key, node);
        }
    }
}

std::string to_toml_string(const toml::table& table)
{
    std::ostringstream ss;
    ss << table;
    return ss.str();
}

std::string toml_value_text(const toml::node& value)
{
    if (const auto* f = value.as_floating_point()) {
        // The shortest text that reads back as the same double: "0.1", not "0.10000000000000001".
        const double v = f->get();
        char text[40];
        for (int digits = 1; digits <= 17; ++digits) {
            std::snprintf(text, sizeof text, "%.*g", digits, v);
            if (std::strtod(text, nullptr) == v) break;
        }
        std::string out = text;
        if (out.find_first_of(".eni") == std::string::npos) out += ".0";
        return out;
    }
    std::ostringstream out;
    value.visit([&](const auto& v) { out << v; });
    return out.str();
}

} // namespace lb
