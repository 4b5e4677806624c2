#include "io/table_data.hpp"

#include <toml++/toml.h>

#include "core/error.hpp"
#include "io/atomic_file.hpp"
#include "io/toml_config.hpp"

namespace lb {

namespace {

toml::array string_array(const std::vector<std::string>& items)
{
    toml::array a;
    for (const std::string& s : items) a.push_back(s);
    return a;
}

std::string text_of(const toml::table& t, const char* key, const std::string& source)
{
    const auto v = t[key].value<std::string>();
    if (!v) throw IoError(source + ": key '" + key + "' is missing or not a string");
    return *v;
}

std::vector<std::string> strings_of(const toml::table& t, const char* key, const std::string& source)
{
    const toml::array* a = t[key].as_array();
    if (!a) throw IoError(source + ": key '" + key + "' is missing or not an array");
    std::vector<std::string> out;
    for (const toml::node& n : *a) {
        const auto s = n.value<std::string>();
        if (!s) throw IoError(source + ": '" + key + "' holds a non-string entry");
        out.push_back(*s);
    }
    return out;
}

} // namespace

std::string to_table_toml(const Table& table)
{
    toml::table t;
    t.insert("title", table.title);
    t.insert("caption", table.caption);
    t.insert("label", table.label);
    t.insert("columns", string_array(table.columns));
    t.insert("notes", string_array(table.notes));
    toml::array rows;
    for (const auto& row : table.rows) {
        toml::array cells;
        for (const TableCell& c : row) {
            toml::table cell;
            cell.insert("text", c.text);
            if (c.value) cell.insert("value", *c.value);
            cells.push_back(std::move(cell));
        }
        rows.push_back(std::move(cells));
    }
    t.insert("rows", std::move(rows));
    return to_toml_string(t);
}

Table parse_table_toml(const std::string& text, const std::string& source)
{
    toml::table t;
    try {
        t = parse_toml(text, source);
    } catch (const Error& e) {
        throw IoError(std::string("not a table file: ") + e.what());
    }
    Table out;
    out.title = text_of(t, "title", source);
    out.caption = text_of(t, "caption", source);
    out.label = text_of(t, "label", source);
    out.columns = strings_of(t, "columns", source);
    out.notes = strings_of(t, "notes", source);
    const toml::array* rows = t["rows"].as_array();
    if (!rows) throw IoError(source + ": key 'rows' is missing or not an array");
    for (size_t r = 0; r < rows->size(); ++r) {
        const toml::array* cells = (*rows)[r].as_array();
        const std::string where = source + ": row " + std::to_string(r + 1);
        if (!cells) throw IoError(where + " is not an array of cells");
        if (cells->size() != out.columns.size())
            throw IoError(where + " has " + std::to_string(cells->size()) + " cells for " +
                          std::to_string(out.columns.size()) + " columns");
        std::vector<TableCell> row;
        for (const toml::node& n : *cells) {
            const toml::table* cell = n.as_table();
            if (!cell) throw IoError(where + " holds a cell that is not a table {text, value}");
            TableCell c(text_of(*cell, "text", where));
            if (const toml::node* v = cell->get("value")) {
                const auto d = v->value<double>();  // an integer reads as a double too
                if (!d) throw IoError(where + ": a cell's 'value' is not a number");
                c.value = *d;
            }
            row.push_back(std::move(c));
        }
        out.rows.push_back(std::move(row));
    }
    return out;
}

std::string write_table_data(const Table& table, const std::string& stem)
{
    const std::string path = stem + ".table.toml";
    write_text_atomically(path, to_table_toml(table));
    return path;
}

Table read_table_data(const std::string& path) { return parse_table_toml(read_text_file(path), path); }

} // namespace lb
