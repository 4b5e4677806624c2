#include "lb_paths.hpp"
#include "io/table.hpp"

#include <sys/utsname.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>

#include "core/build_info.hpp"
#include "core/error.hpp"
#include "core/parallel.hpp"
#include "io/atomic_file.hpp"

#ifndef LB_BUILD_TYPE
#define LB_BUILD_TYPE "unknown"
#endif

namespace lb {
namespace {

std::string with_unit(std::string text, const std::string& unit)
{
    if (!unit.empty()) text += " " + unit;
    return text;
}

std::string non_finite_text(double v)
{
    if (std::isnan(v)) return "NaN";
    return v > 0 ? "inf" : "-inf";
}

/// Terminal/display width of UTF-8 text: count code points, not bytes ("—" is one column).
size_t display_width(const std::string& s)
{
    return size_t(std::count_if(s.begin(), s.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xC0) != 0x80; }));
}

std::string one_line(const std::string& s)
{
    std::string out = s;
    std::replace(out.begin(), out.end(), '\n', ' ');
    std::replace(out.begin(), out.end(), '\r', ' ');
    return out;
}

std::string markdown_escape(const std::string& s)
{
    std::string out;
    for (char c : one_line(s)) {
        if (c == '|') out += '\\';
        out += c;
    }
    return out;
}

std::string csv_number(double v)
{
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char buffer[64];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
    return std::string(buffer, result.ptr);
}

std::string csv_field(const std::string& s)
{
    const bool quote = s.find_first_of(",\"#\n\r") != std::string::npos ||
                       (!s.empty() && (s.front() == ' ' || s.back() == ' '));
    if (!quote) return s;
    std::string out = "\"";
    for (char c : s) {
        if (c == '"') out += '"';
        out += c;
    }
    return out + "\"";
}

void check_shape(const Table& table)
{
    if (table.columns.empty()) throw Error("table '" + table.title + "' has no columns");
    for (size_t r = 0; r < table.rows.size(); ++r) {
        if (table.rows[r].size() != table.columns.size()) {
            throw Error("table '" + table.title + "': row " + std::to_string(r) + " has " +
                        std::to_string(table.rows[r].size()) + " cells for " + std::to_string(table.columns.size()) +
                        " columns");
        }
    }
}

} // namespace

std::string utc_now()
{
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char buffer[64];
    std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H:%M UTC", &tm);
    return buffer;
}

namespace {

std::string trim(const std::string& s)
{
    const auto begin = s.find_first_not_of(" \t");
    if (begin == std::string::npos) return "";
    const auto end = s.find_last_not_of(" \t\r\n");
    return s.substr(begin, end - begin + 1);
}

} // namespace

// ---- cells and tables ---------------------------------------------------------

TableCell TableCell::fixed(double v, int decimals, const std::string& unit)
{
    if (!std::isfinite(v)) return {with_unit(non_finite_text(v), unit), v};
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.*f", std::max(decimals, 0), v);
    return {with_unit(buffer, unit), v};
}

TableCell TableCell::significant(double v, int digits, const std::string& unit)
{
    if (!std::isfinite(v)) return {with_unit(non_finite_text(v), unit), v};
    char buffer[64];
    std::snprintf(buffer, sizeof(buffer), "%.*g", std::max(digits, 1), v);
    return {with_unit(buffer, unit), v};
}

TableCell TableCell::integer(long long v, const std::string& unit)
{
    const std::string digits = std::to_string(v < 0 ? -(unsigned long long)v : (unsigned long long)v);
    std::string grouped;
    for (size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) grouped += ',';
        grouped += digits[i];
    }
    return {with_unit((v < 0 ? "-" : "") + grouped, unit), double(v)};
}

TableCell TableCell::missing(const std::string& text)
{
    return {text, std::numeric_limits<double>::quiet_NaN()};
}

void Table::add_row(std::vector<TableCell> cells)
{
    if (cells.size() != columns.size()) {
        throw Error("table '" + title + "': a row of " + std::to_string(cells.size()) + " cells for " +
                    std::to_string(columns.size()) + " columns");
    }
    rows.push_back(std::move(cells));
}

void Table::add_provenance(const std::string& threads) { add_note(provenance_note(threads)); }

bool Table::is_numeric_column(size_t c) const
{
    bool any = false;
    for (const auto& row : rows) {
        if (c >= row.size() || row[c].text.empty()) continue;
        if (!row[c].value) return false;
        any = true;
    }
    return any;
}

// ---- provenance -------------------------------------------------------------

std::string machine_description()
{
    std::string cpu;
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (cpu.empty() && std::getline(cpuinfo, line)) {
        const auto colon = line.find(':');
        if (colon == std::string::npos) continue;
        const std::string key = trim(line.substr(0, colon));
        // x86 uses "model name"; some ARM kernels only give "Hardware" or "Processor".
        if (key == "model name" || key == "Hardware" || key == "Processor") cpu = trim(line.substr(colon + 1));
    }
    if (cpu.empty()) cpu = "unknown CPU";
    std::string result = cpu + " (" + std::to_string(std::max(1u, std::thread::hardware_concurrency())) + " logical cores";
    utsname names{};
    if (uname(&names) == 0) result += std::string(", ") + names.machine;
    return result + ")";
}

std::string provenance_note(const std::string& threads)
{
    return "machine: " + machine_description() + "; threads: " + (threads.empty() ? std::to_string(num_threads()) : threads) +
           "; build: " + std::string(LB_BUILD_TYPE) + "; commit: " + build_commit_short() + "; date: " + utc_now();
}

// ---- Markdown -----------------------------------------------------------------

std::string to_markdown(const Table& table)
{
    check_shape(table);
    const size_t n = table.columns.size();
    std::vector<std::string> header(n);
    std::vector<std::vector<std::string>> body(table.rows.size(), std::vector<std::string>(n));
    std::vector<size_t> width(n, 3);
    for (size_t c = 0; c < n; ++c) {
        header[c] = markdown_escape(table.columns[c]);
        width[c] = std::max(width[c], display_width(header[c]));
        for (size_t r = 0; r < table.rows.size(); ++r) {
            body[r][c] = markdown_escape(table.rows[r][c].text);
            width[c] = std::max(width[c], display_width(body[r][c]));
        }
    }
    std::vector<bool> numeric(n);
    for (size_t c = 0; c < n; ++c) numeric[c] = table.is_numeric_column(c);

    auto pad = [&](const std::string& s, size_t c) {
        const std::string fill(width[c] - display_width(s), ' ');
        return numeric[c] ? fill + s : s + fill;
    };
    std::ostringstream out;
    if (!table.title.empty()) out << "## " << one_line(table.title) << "\n\n";
    if (!table.caption.empty()) out << one_line(table.caption) << "\n\n";
    out << "|";
    for (size_t c = 0; c < n; ++c) out << " " << pad(header[c], c) << " |";
    out << "\n|";
    for (size_t c = 0; c < n; ++c) {
        out << (numeric[c] ? std::string(width[c] + 1, '-') + ":" : ":" + std::string(width[c] + 1, '-')) << "|";
    }
    out << "\n";
    for (const auto& row : body) {
        out << "|";
        for (size_t c = 0; c < n; ++c) out << " " << pad(row[c], c) << " |";
        out << "\n";
    }
    if (!table.notes.empty()) {
        out << "\n";
        for (const auto& note : table.notes) out << "- " << one_line(note) << "\n";
    }
    return out.str();
}

// ---- CSV ----------------------------------------------------------------------

std::string to_csv(const Table& table)
{
    check_shape(table);
    std::ostringstream out;
    if (!table.title.empty()) out << "# " << one_line(table.title) << "\n";
    if (!table.caption.empty()) out << "# " << one_line(table.caption) << "\n";
    for (const auto& note : table.notes) out << "# " << one_line(note) << "\n";
    for (size_t c = 0; c < table.columns.size(); ++c) out << (c ? "," : "") << csv_field(table.columns[c]);
    out << "\n";
    for (const auto& row : table.rows) {
        for (size_t c = 0; c < row.size(); ++c) {
            out << (c ? "," : "") << (row[c].value ? csv_number(*row[c].value) : csv_field(row[c].text));
        }
        out << "\n";
    }
    return out.str();
}

// ---- LaTeX --------------------------------------------------------------------

std::string latex_escape(const std::string& text)
{
    std::string out;
    for (char c : one_line(text)) {
        switch (c) {
        case '&': case '%': case '$': case '#': case '_': case '{': case '}':
            out += '\\';
            out += c;
            break;
        case '~': out += "\\textasciitilde{}"; break;
        case '^': out += "\\textasciicircum{}"; break;
        case '\\': out += "\\textbackslash{}"; break;
        case '<': out += "\\textless{}"; break;
        case '>': out += "\\textgreater{}"; break;
        case '|': out += "\\textbar{}"; break;
        default: out += c;
        }
    }
    return out;
}

namespace {

/// The value of a CSV field if the whole field is a number (to_csv's spelling), else none.
std::optional<double> csv_value(const std::string& field)
{
    if (field.empty()) return std::nullopt;
    double v = 0.0;
    const char* end = field.data() + field.size();
    const auto result = std::from_chars(field.data(), end, v);
    if (result.ec != std::errc() || result.ptr != end) return std::nullopt;
    return v;
}

} // namespace

Table parse_csv(const std::string& text, const std::string& source)
{
    Table table;
    size_t pos = 0, line = 1;
    // Leading "# " comment lines: title, caption, then notes.
    std::vector<std::string> comments;
    while (pos < text.size() && text[pos] == '#') {
        size_t end = text.find('\n', pos);
        if (end == std::string::npos) end = text.size();
        std::string c = text.substr(pos + 1, end - pos - 1);
        if (!c.empty() && c.front() == ' ') c.erase(0, 1);
        comments.push_back(std::move(c));
        pos = std::min(end + 1, text.size());
        ++line;
    }
    if (!comments.empty()) table.title = comments[0];
    if (comments.size() > 1) table.caption = comments[1];
    for (size_t k = 2; k < comments.size(); ++k) table.notes.push_back(comments[k]);

    // RFC 4180 records: quoted fields may hold ',', '"' (doubled) and line breaks.
    std::vector<std::vector<TableCell>> records;
    std::vector<size_t> record_lines;
    std::vector<TableCell> record;
    std::string field;
    bool quoted = false, field_was_quoted = false;
    size_t record_line = line;
    auto end_field = [&] {
        TableCell cell(field);
        if (!field_was_quoted) cell.value = csv_value(field);
        record.push_back(std::move(cell));
        field.clear();
        field_was_quoted = false;
    };
    auto end_record = [&] {
        end_field();
        if (!(record.size() == 1 && record[0].text.empty() && !record[0].value)) {  // blank line
            records.push_back(std::move(record));
            record_lines.push_back(record_line);
        }
        record.clear();
    };
    for (; pos < text.size(); ++pos) {
        const char c = text[pos];
        if (quoted) {
            if (c == '"' && pos + 1 < text.size() && text[pos + 1] == '"') {
                field += '"';
                ++pos;
            } else if (c == '"') {
                quoted = false;
            } else {
                if (c == '\n') ++line;
                field += c;
            }
        } else if (c == '"' && field.empty()) {
            quoted = field_was_quoted = true;
        } else if (c == ',') {
            end_field();
        } else if (c == '\n') {
            end_record();
            record_line = ++line;
        } else if (c != '\r') {
            field += c;
        }
    }
    if (quoted) throw IoError(source + ":" + std::to_string(record_line) + ": a quoted field is not closed");
    if (!field.empty() || !record.empty() || field_was_quoted) end_record();
    if (records.empty()) throw IoError(source + ": no header line (an empty table file)");
    for (TableCell& c : records[0]) table.columns.push_back(c.text);
    for (size_t r = 1; r < records.size(); ++r) {
        if (records[r].size() != table.columns.size()) {
            throw IoError(source + ":" + std::to_string(record_lines[r]) + ": " + std::to_string(records[r].size()) +
                          " fields where the header has " + std::to_string(table.columns.size()));
        }
        table.rows.push_back(std::move(records[r]));
    }
    return table;
}

Table read_csv(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot read table " + path + ": " + std::strerror(errno));
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw IoError("cannot read table " + path);
    return parse_csv(ss.str(), path);
}

std::string to_latex(const Table& table)
{
    check_shape(table);
    const size_t n = table.columns.size();
    std::ostringstream out;
    out << "% " << one_line(table.title.empty() ? "table" : table.title) << " (generated by latentbench; needs \\usepackage{booktabs})\n";
    out << "\\begin{table}[htbp]\n  \\centering\n";
    if (!table.title.empty() || !table.caption.empty()) {
        out << "  \\caption{";
        if (!table.title.empty()) {
            out << "\\textbf{" << latex_escape(table.title);
            const char last = table.title.back();
            if (last != '.' && last != ':' && last != '?' && last != '!') out << ".";
            out << "}";
            if (!table.caption.empty()) out << " ";
        }
        out << latex_escape(table.caption) << "}\n";
    }
    if (!table.label.empty()) out << "  \\label{" << table.label << "}\n";
    out << "  \\begin{tabular}{";
    for (size_t c = 0; c < n; ++c) out << (table.is_numeric_column(c) ? 'r' : 'l');
    out << "}\n    \\toprule\n    ";
    for (size_t c = 0; c < n; ++c) out << (c ? " & " : "") << latex_escape(table.columns[c]);
    out << " \\\\\n    \\midrule\n";
    for (const auto& row : table.rows) {
        out << "    ";
        for (size_t c = 0; c < n; ++c) out << (c ? " & " : "") << latex_escape(row[c].text);
        out << " \\\\\n";
    }
    out << "    \\bottomrule\n  \\end{tabular}\n";
    if (!table.notes.empty()) {
        out << "  \\par\\smallskip\n  {\\footnotesize\n";
        for (const auto& note : table.notes) out << "  " << latex_escape(note) << "\\par\n";
        out << "  }\n";
    }
    out << "\\end{table}\n";
    return out.str();
}

// ---- files --------------------------------------------------------------------

void write_markdown(const Table& table, const std::string& path) { write_text_atomically(path, to_markdown(table)); }
void write_csv(const Table& table, const std::string& path) { write_text_atomically(path, to_csv(table)); }
void write_latex(const Table& table, const std::string& path) { write_text_atomically(path, to_latex(table)); }

std::vector<std::string> write_table_files(const Table& table, const std::string& stem)
{
    std::vector<std::string> paths = {stem + ".md", stem + ".csv", stem + ".tex"};
    write_markdown(table, paths[0]);
    write_csv(table, paths[1]);
    write_latex(table, paths[2]);
    return paths;
}

} // namespace lb
