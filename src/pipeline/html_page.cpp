#include "lb_paths.hpp"

#include "pipeline/html_page.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include <toml++/toml.h>

#include "core/error.hpp"
#include "core/process.hpp"
#include "io/atomic_file.hpp"
#include "io/json.hpp"
#include "io/table.hpp"
#include "io/table_data.hpp"
#include "io/toml_config.hpp"

namespace lb {
namespace fs = std::filesystem;

namespace {

constexpr const char* kGit = "/usr/bin/git";

/// Text for HTML content and attribute values: & < > " ' escaped.
std::string esc(const std::string& s)
{
    std::string out;
    out.reserve(s.size());
    for (const char c : s) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        case '\'': out += "&#39;"; break;
        default: out += c;
        }
    }
    return out;
}

/// A relative path as a URL (every byte but unreserved characters and '/' percent-encoded),
/// then escaped for an attribute.
std::string url(const std::string& relative)
{
    static const char* hex = "0123456789ABCDEF";
    std::string out;
    for (const unsigned char c : relative) {
        if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~' || c == '/') {
            out += char(c);
        } else {
            out += '%';
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return esc(out);
}

/// An id for an anchor: letters, digits, '-' and '_' kept, everything else '-'.
std::string anchor(const std::string& s)
{
    std::string out;
    for (const unsigned char c : s) out += (std::isalnum(c) || c == '_' || c == '-') ? char(c) : '-';
    return out;
}

/// The standard output of a program (run without a shell); "" if it fails.
std::string output_of(const std::vector<std::string>& argv)
{
    if (!fs::exists(argv.front())) return "";
    const fs::path out = fs::temp_directory_path() / ("lb_page_" + std::to_string(::getpid()) + ".out");
    const fs::path err = fs::temp_directory_path() / ("lb_page_" + std::to_string(::getpid()) + ".err");
    int status = -1;
    try {
        status = run_process(argv, {out.string(), err.string(), false, 30.0});
    } catch (const Error&) {
        status = -1;
    }
    std::string text;
    if (status == 0) {
        std::ifstream in(out);
        std::stringstream ss;
        ss << in.rdbuf();
        text = ss.str();
        while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    }
    std::error_code ec;
    fs::remove(out, ec);
    fs::remove(err, ec);
    return text;
}

// ---- the folder's contents ---------------------------------------------------------

struct LoadedTable {
    Table table;
    std::string stem;  ///< relative to the suite folder, e.g. "tables/methods_cloth"
    bool from_csv = false;
};

struct SceneFiles {
    std::string label;
    std::optional<LoadedTable> methods, diagnose, embedding, deviations;
    std::vector<LoadedTable> ablations;
    std::map<std::string, std::set<double>> seeds;  ///< method + '\x1f' + sweep point -> seeds
    bool seeds_known = false;
    std::string filmstrip;                      ///< relative path, "" if none
    std::vector<std::string> videos, plots, training;
};

struct Suite {
    std::string dir;
    std::string name, description;
    std::string tables_rel;  ///< "tables" or ""
    std::vector<SceneFiles> scenes;
    std::vector<LoadedTable> paper_tables, other_tables;
    std::vector<std::string> other_figures, other_videos;
    bool any_csv = false;
};

std::string join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "/" + b; }

bool ends_with(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::vector<std::string> files_in(const fs::path& dir, const std::string& extension)
{
    std::vector<std::string> names;
    if (!fs::is_directory(dir)) return names;
    for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        if (e.is_regular_file() && ends_with(name, extension)) names.push_back(name);
    }
    std::sort(names.begin(), names.end());
    return names;
}

/// The scene label a file named `<label><rest>` belongs to: the longest label followed by
/// `rest_start` characters ('_' or '.'); "" if none.
std::string owner(const std::string& name, const std::vector<std::string>& labels)
{
    std::string best;
    for (const std::string& l : labels) {
        if (name.size() > l.size() && name.compare(0, l.size(), l) == 0 && (name[l.size()] == '.' || name[l.size()] == '_') &&
            l.size() > best.size())
            best = l;
    }
    return best;
}

/// The label `stem` ends with ("_<label>"), the longest; "" if none.
std::string suffix_label(const std::string& stem, const std::vector<std::string>& labels)
{
    std::string best;
    for (const std::string& l : labels) {
        if (ends_with(stem, "_" + l) && l.size() > best.size()) best = l;
    }
    return best;
}

Suite scan(const std::string& dir)
{
    Suite s;
    s.dir = dir;
    if (!fs::is_directory(dir)) throw IoError("'" + dir + "' is not a directory");
    s.tables_rel = fs::is_directory(fs::path(dir) / "tables") ? "tables" : "";
    const fs::path tables = fs::path(dir) / s.tables_rel;
    s.name = fs::path(dir).lexically_normal().filename().string();
    if (s.name.empty()) s.name = fs::path(dir).lexically_normal().parent_path().filename().string();
    const fs::path toml_path = fs::path(dir) / "experiment.toml";
    if (fs::exists(toml_path)) {
        const toml::table t = parse_toml_file(toml_path.string());
        if (const auto n = t["name"].value<std::string>()) s.name = *n;
        if (const auto d = t["description"].value<std::string>()) s.description = *d;
    }

    // Every table stem, from its structured twin if there is one, else from its CSV.
    std::set<std::string> stems;
    for (const std::string& f : files_in(tables, ".table.toml")) stems.insert(f.substr(0, f.size() - 11));
    for (const std::string& f : files_in(tables, ".csv")) stems.insert(f.substr(0, f.size() - 4));
    auto load = [&](const std::string& stem) {
        LoadedTable t;
        t.stem = join(s.tables_rel, stem);
        const fs::path twin = tables / (stem + ".table.toml");
        if (fs::exists(twin)) {
            t.table = read_table_data(twin.string());
        } else {
            t.table = read_csv((tables / (stem + ".csv")).string());
            t.from_csv = true;
            s.any_csv = true;
        }
        return t;
    };
    std::vector<std::string> labels;
    for (const std::string& stem : stems) {
        if (stem.rfind("methods_", 0) == 0) labels.push_back(stem.substr(8));
    }
    if (labels.empty())
        throw IoError("'" + dir + "' holds no methods table (" + join(s.tables_rel, "methods_<scene>.csv") +
                      "): not a suite's output folder");
    for (const std::string& l : labels) {
        SceneFiles f;
        f.label = l;
        s.scenes.push_back(std::move(f));
    }
    auto scene = [&](const std::string& label) -> SceneFiles& {
        return *std::find_if(s.scenes.begin(), s.scenes.end(), [&](const SceneFiles& f) { return f.label == label; });
    };
    for (const std::string& stem : stems) {
        const auto has = [&](const std::string& prefix, std::string& label) {
            if (stem.rfind(prefix, 0) != 0) return false;
            const std::string rest = stem.substr(prefix.size());
            if (std::find(labels.begin(), labels.end(), rest) == labels.end()) return false;
            label = rest;
            return true;
        };
        std::string l;
        if (has("methods_", l)) {
            scene(l).methods = load(stem);
        } else if (has("diagnose_", l)) {
            scene(l).diagnose = load(stem);
        } else if (has("embedding_", l)) {
            scene(l).embedding = load(stem);
        } else if (has("deviations_", l)) {
            scene(l).deviations = load(stem);
        } else if (has("rollouts_", l) || (has("observations_", l) && !fs::exists(tables / ("rollouts_" + l + ".csv")))) {
            // The tidy table's seed column is a number in its CSV: read exactly.
            const Table obs = read_csv((tables / (stem + ".csv")).string());
            const auto col = [&](const char* name) {
                const auto it = std::find(obs.columns.begin(), obs.columns.end(), name);
                return it == obs.columns.end() ? -1 : int(it - obs.columns.begin());
            };
            const int method = col("method"), point = col("sweep point"), seed = col("seed");
            if (method < 0 || seed < 0) continue;
            SceneFiles& f = scene(l);
            f.seeds_known = true;
            for (const auto& row : obs.rows) {
                std::set<double>& seeds = f.seeds[row[size_t(method)].text + '\x1f' + (point >= 0 ? row[size_t(point)].text : "")];
                if (row[size_t(seed)].value && std::isfinite(*row[size_t(seed)].value)) seeds.insert(*row[size_t(seed)].value);
            }
        } else if (has("training_", l) || has("observations_", l)) {
            // Tidy data beside the tables (the training curves are shown as figures; an
            // older observations_ file duplicates rollouts_): not a table to show.
            continue;
        } else if (stem.rfind("ablation_", 0) == 0 && !suffix_label(stem, labels).empty()) {
            scene(suffix_label(stem, labels)).ablations.push_back(load(stem));
        } else if (stem == "table1_timings" || stem == "table2_jvp") {
            s.paper_tables.push_back(load(stem));
        } else {
            s.other_tables.push_back(load(stem));
        }
    }
    // Figures and videos: a scene's own by name, the rest under "other".
    const fs::path figures = fs::path(dir) / "figures";
    for (const std::string& f : files_in(figures, ".png")) {
        const std::string l = owner(f, labels);
        if (!l.empty() && f == l + "_filmstrip.png") scene(l).filmstrip = "figures/" + f;
        else s.other_figures.push_back("figures/" + f);
    }
    for (SceneFiles& f : s.scenes) {
        for (const std::string& png : files_in(figures / f.label, ".png")) {
            (png.rfind("training_", 0) == 0 ? f.training : f.plots).push_back("figures/" + f.label + "/" + png);
        }
    }
    for (const std::string& v : files_in(fs::path(dir) / "videos", ".mp4")) {
        const std::string l = v.substr(0, v.size() - 4);
        if (std::find(labels.begin(), labels.end(), l) != labels.end()) scene(l).videos.push_back("videos/" + v);
        else s.other_videos.push_back("videos/" + v);
    }
    return s;
}

// ---- rendering ---------------------------------------------------------------------

constexpr const char* kStyle = R"(
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0 auto;max-width:1500px;padding:0 18px 40px;color:#1b1b1b}
h1{margin:18px 0 4px}h2{border-bottom:2px solid #ccc;padding-bottom:3px;margin-top:34px}h3{margin:22px 0 6px}
nav a{margin-right:12px}.note{background:#fff6d5;border:1px solid #e5c96a;padding:8px 12px;border-radius:4px}
.scroll{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:12.5px;margin:6px 0}
th,td{border:1px solid #ccc;padding:3px 6px;vertical-align:top}
th{background:#eef1f5;cursor:pointer;user-select:none;white-space:nowrap;position:sticky;top:0}
th::after{content:" \2195";color:#999}th[aria-sort=ascending]::after{content:" \2191";color:#000}
th[aria-sort=descending]::after{content:" \2193";color:#000}
td.num{text-align:right;font-variant-numeric:tabular-nums;white-space:nowrap}
td.diverged{background:#fbd3d0;color:#8a0b00;font-weight:600}
tbody tr:nth-child(even){background:#fafafa}
details.caption{margin:2px 0 4px;color:#444;max-width:1100px}details.caption summary{cursor:pointer;color:#225}
ul.notes{margin:2px 0;color:#555;font-size:12px}.files{font-size:12px;color:#555}
.gallery{display:flex;flex-wrap:wrap;gap:10px}.gallery figure{margin:0;flex:0 1 460px}
.gallery img{width:100%;border:1px solid #ddd}.wide img{max-width:100%;border:1px solid #ddd}
figcaption{font-size:12px;color:#555}video{max-width:100%;border:1px solid #ddd;background:#000}
dl.prov{display:grid;grid-template-columns:max-content auto;gap:2px 14px}dl.prov dt{font-weight:600}dl.prov dd{margin:0;word-break:break-all}
.missing{color:#777;font-style:italic}
)";

// Sort a table by the clicked header: numbers (data-v) ascending then descending, text
// by locale; cells without a number after those with one. Stable, so ties keep order.
constexpr const char* kScript = R"(
document.querySelectorAll('table.sortable').forEach(function (table) {
  var heads = table.tHead.rows[0].cells;
  Array.prototype.forEach.call(heads, function (th, col) {
    th.addEventListener('click', function () {
      var up = th.getAttribute('aria-sort') !== 'ascending';
      Array.prototype.forEach.call(heads, function (h) { h.removeAttribute('aria-sort'); });
      th.setAttribute('aria-sort', up ? 'ascending' : 'descending');
      var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
      function key(row) {
        var c = row.cells[col], v = c.getAttribute('data-v');
        var n = v === null ? NaN : parseFloat(v);
        return {n: n, t: c.textContent};
      }
      rows.sort(function (a, b) {
        var x = key(a), y = key(b), r;
        var xn = !isNaN(x.n), yn = !isNaN(y.n);
        if (xn && yn) r = x.n - y.n;
        else if (xn !== yn) return xn ? -1 : 1;
        else r = x.t.localeCompare(y.t, undefined, {numeric: true});
        return up ? r : -r;
      });
      rows.forEach(function (row) { body.appendChild(row); });
    });
  });
});
)";

std::string number_text(double v)
{
    if (std::isnan(v)) return "nan";
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

std::string cell_html(const TableCell& c, bool from_csv)
{
    std::string text = c.text;
    // The CSV keeps a numeric cell's value, not its text: shown to 4 significant digits.
    if (from_csv && c.value) text = std::isfinite(*c.value) ? TableCell::significant(*c.value, 4).text : "—";
    const bool diverged = c.text.find("diverged") != std::string::npos;
    std::string classes;
    if (c.value) classes += "num";
    if (diverged) classes += std::string(classes.empty() ? "" : " ") + "diverged";
    std::string out = "<td";
    if (!classes.empty()) out += " class=\"" + classes + "\"";
    if (c.value) out += " data-v=\"" + esc(number_text(*c.value)) + "\"";
    if (diverged) out += " title=\"the rollout diverged (blew up) in this window\"";
    return out + ">" + esc(text) + "</td>";
}

/// A sortable table with its caption (folded), notes and links to its files. `seeds`, if
/// given, adds a "seeds" column after "method" (the seeds each row's method ran with).
std::string table_html(const Suite& s, const LoadedTable& t, const std::string& id, const SceneFiles* seeds = nullptr)
{
    const Table& table = t.table;
    const auto column = [&](const char* name) {
        const auto it = std::find(table.columns.begin(), table.columns.end(), name);
        return it == table.columns.end() ? -1 : int(it - table.columns.begin());
    };
    const int method_col = column("method"), point_col = column("sweep point");
    // Today's methods tables count their seeds themselves (a 'seeds' column): no second one.
    const bool with_seeds = seeds && seeds->seeds_known && method_col >= 0 && column("seeds") < 0;
    std::ostringstream o;
    o << "<div class=\"table-block\">\n<h4>" << esc(table.title) << "</h4>\n";
    if (!table.caption.empty())
        o << "<details class=\"caption\"><summary>caption</summary>" << esc(table.caption) << "</details>\n";
    o << "<div class=\"scroll\"><table class=\"sortable\" id=\"" << esc(id) << "\"><thead><tr>";
    for (size_t c = 0; c < table.columns.size(); ++c) {
        o << "<th>" << esc(table.columns[c]) << "</th>";
        if (with_seeds && int(c) == method_col) o << "<th>seeds</th>";
    }
    o << "</tr></thead>\n<tbody>\n";
    for (const auto& row : table.rows) {
        o << "<tr>";
        for (size_t c = 0; c < row.size(); ++c) {
            o << cell_html(row[c], t.from_csv);
            if (with_seeds && int(c) == method_col) {
                const std::string point = point_col >= 0 ? row[size_t(point_col)].text : "";
                auto it = seeds->seeds.find(row[c].text + '\x1f' + point);
                if (it == seeds->seeds.end()) {
                    o << "<td class=\"missing\">not in observations</td>";
                } else if (it->second.empty()) {
                    o << "<td class=\"num\" data-v=\"1\" title=\"one run without a seed list\">1 (no seed)</td>";
                } else {
                    std::string list;
                    for (const double v : it->second) list += (list.empty() ? "" : ", ") + number_text(v);
                    o << "<td class=\"num\" data-v=\"" << it->second.size() << "\" title=\"seeds " << esc(list) << "\">"
                      << it->second.size() << " (" << esc(list) << ")</td>";
                }
            }
        }
        o << "</tr>\n";
    }
    o << "</tbody></table></div>\n";
    if (!table.notes.empty()) {
        o << "<ul class=\"notes\">";
        for (const std::string& n : table.notes) o << "<li>" << esc(n) << "</li>";
        o << "</ul>\n";
    }
    o << "<p class=\"files\">";
    if (t.from_csv)
        o << "Read from the CSV (numbers only; the Markdown's cell texts, such as diverged markers, are not in it). ";
    o << "Files:";
    for (const char* ext : {".md", ".csv", ".tex", ".table.toml"}) {
        if (fs::exists(fs::path(s.dir) / (t.stem + ext))) o << " <a href=\"" << url(t.stem + ext) << "\">" << esc(ext + 1) << "</a>";
    }
    o << "</p>\n</div>\n";
    return o.str();
}

std::string gallery_html(const std::vector<std::string>& images)
{
    std::ostringstream o;
    o << "<div class=\"gallery\">\n";
    for (const std::string& p : images) {
        const std::string name = fs::path(p).filename().string();
        o << "<figure><a href=\"" << url(p) << "\"><img src=\"" << url(p) << "\" alt=\"" << esc(name) << "\"></a><figcaption>"
          << esc(name) << "</figcaption></figure>\n";
    }
    return o.str() + "</div>\n";
}

std::string video_html(const std::string& path)
{
    return "<figure><video controls muted loop playsinline preload=\"metadata\" src=\"" + url(path) + "\"></video><figcaption>" +
           esc(fs::path(path).filename().string()) + "</figcaption></figure>\n";
}

std::string missing_html(const std::string& what) { return "<p class=\"missing\">" + esc(what) + "</p>\n"; }

/// A provenance.json value as text: strings as they are, arrays joined, "not recorded" for null.
std::string provenance_text(const JsonValue& v)
{
    switch (v.type) {
    case JsonValue::Type::string: return v.str;
    case JsonValue::Type::number: return TableCell::significant(v.num, 12).text;
    case JsonValue::Type::boolean: return v.b ? "true" : "false";
    case JsonValue::Type::null: return "not recorded";
    case JsonValue::Type::array: {
        std::string out;
        for (const JsonValue& e : v.arr) {
            std::string a = provenance_text(e);
            if (a.empty() || a.find_first_of(" \t'\"") != std::string::npos) a = "'" + a + "'";
            out += (out.empty() ? "" : " ") + a;
        }
        return out;
    }
    case JsonValue::Type::object: {
        std::string out;
        for (const auto& [key, e] : v.obj) out += (out.empty() ? "" : ", ") + key + " " + provenance_text(e);
        return out;
    }
    }
    return "";
}

/// The provenance list: the run's provenance.json (pipeline/report.hpp, write_provenance;
/// retrofitted for older published folders), else what the folder tells.
std::string provenance_html(const Suite& s)
{
    std::vector<std::pair<std::string, std::string>> items;
    const fs::path file = fs::path(s.dir) / "provenance.json";
    if (fs::exists(file)) {
        std::ifstream in(file);
        std::ostringstream text;
        text << in.rdbuf();
        const JsonValue p = parse_json(text.str(), file.string(), 1 << 20, 16);
        const auto get = [&](const char* key) { return p.has(key) ? provenance_text(p.at(key)) : std::string("not recorded"); };
        std::string commit = get("commit");
        if (p.has("dirty") && p.at("dirty").type == JsonValue::Type::boolean && p.at("dirty").b)
            commit += " (uncommitted changes)";
        if (p.has("commit_kind")) commit += " — " + get("commit_kind");
        items = {{"commit", commit},
                 {"command", get("command")},
                 {"suite file", get("suite_file") + " (" + get("suite_hash") + ")"},
                 {"seeds", get("seeds").empty() ? "none (each method's own)" : get("seeds")},
                 {"threads", get("threads")},
                 {"fit versions", get("fit_versions")},
                 {"machine", p.has("machine") ? get("machine") : "not recorded"},
                 {"date", p.has("date") ? get("date") : "not recorded"}};
    } else {
        // A published folder: the last commit that changed it, and the tables' own notes.
        // (the page itself aside, or committing it would name its own commit)
        const std::string commit =
            output_of({kGit, "-C", s.dir, "log", "-1", "--format=%H (%cd)", "--date=iso", "--", ".", ":(exclude)index.html"});
        items.push_back({"commit", commit.empty() ? "not known (no provenance.json, and no git commit has changed this folder)"
                                                  : commit + " — the last commit that changed this folder's outputs"});
        items.push_back({"command", "not recorded (no provenance.json in this folder)"});
        std::string note;
        for (const SceneFiles& f : s.scenes) {
            if (!f.methods) continue;
            for (const std::string& n : f.methods->table.notes) {
                if (n.rfind("machine:", 0) == 0) note = n;
            }
            if (!note.empty()) break;
        }
        items.push_back({"machine, threads, build, date", note.empty() ? "not known" : note + " (the methods table's note)"});
    }
    if (fs::exists(fs::path(s.dir) / "experiment.toml"))
        items.push_back({"suite", "experiment.toml"});
    std::ostringstream o;
    o << "<dl class=\"prov\">\n";
    for (const auto& [k, v] : items) {
        o << "<dt>" << esc(k) << "</dt><dd>";
        if (k == "suite") o << "<a href=\"experiment.toml\">experiment.toml</a> (the resolved suite)";
        else o << esc(v);
        o << "</dd>\n";
    }
    return o.str() + "</dl>\n";
}

std::string scene_html(const Suite& s, const SceneFiles& f)
{
    const std::string a = anchor(f.label);
    std::ostringstream o;
    o << "<section class=\"scene\" id=\"scene-" << a << "\">\n<h2>Scene " << esc(f.label) << "</h2>\n";
    o << "<h3 id=\"methods-" << a << "\">Methods</h3>\n";
    o << "<p class=\"files\">Click a column header to sort. Red cells: the rollout diverged (blew up) in that window. "
      << (f.seeds_known ? "'seeds': how many seeds each method's row combines (from the tidy observations table)."
                        : "Seeds per method: not in this folder (no observations table).")
      << "</p>\n";
    if (f.methods) o << table_html(s, *f.methods, "table-methods-" + a, &f);
    o << "<h3 id=\"filmstrip-" << a << "\">Filmstrip</h3>\n";
    if (!f.filmstrip.empty())
        o << "<div class=\"wide\"><a href=\"" << url(f.filmstrip) << "\"><img src=\"" << url(f.filmstrip) << "\" alt=\"filmstrip of "
          << esc(f.label) << "\"></a></div>\n";
    else o << missing_html("No filmstrip (figures/" + f.label + "_filmstrip.png) in this folder.");
    o << "<h3 id=\"video-" << a << "\">Video</h3>\n";
    for (const std::string& v : f.videos) o << video_html(v);
    if (f.videos.empty()) o << missing_html("No video (videos/" + f.label + ".mp4) in this folder.");
    o << "<h3 id=\"plots-" << a << "\">Per-metric plots</h3>\n";
    if (!f.plots.empty()) o << gallery_html(f.plots);
    else o << missing_html("No plots (figures/" + f.label + "/) in this folder.");
    o << "<h3 id=\"training-" << a << "\">Training curves</h3>\n";
    if (!f.training.empty()) o << gallery_html(f.training);
    else o << missing_html("No training curves (figures/" + f.label + "/training_*.png) in this folder.");
    if (!f.ablations.empty()) {
        o << "<h3 id=\"ablations-" << a << "\">Ablations</h3>\n";
        for (size_t i = 0; i < f.ablations.size(); ++i)
            o << table_html(s, f.ablations[i], "table-ablation-" + a + "-" + std::to_string(i), &f);
    }
    o << "<h3 id=\"diagnose-" << a << "\">Error decomposition</h3>\n";
    if (f.diagnose) o << table_html(s, *f.diagnose, "table-diagnose-" + a);
    else o << missing_html("No error decomposition (the suite's [outputs] diagnose is off).");
    o << "<h3 id=\"embedding-" << a << "\">Embeddings</h3>\n";
    if (f.embedding) o << table_html(s, *f.embedding, "table-embedding-" + a);
    else o << missing_html("No embedding metrics were measured on this scene.");
    o << "<h3 id=\"deviations-" << a << "\">Deviations from the paper's recipe</h3>\n";
    if (f.deviations) o << table_html(s, *f.deviations, "table-deviations-" + a);
    else o << missing_html("No deviations table in this folder.");
    o << "</section>\n";
    return o.str();
}

std::string page_html(const Suite& s)
{
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>" << esc(s.name)
      << " — latentbench suite</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n";
    o << "<header>\n<h1>" << esc(s.name) << "</h1>\n";
    if (!s.description.empty()) o << "<p>" << esc(s.description) << "</p>\n";
    o << "<nav>Scenes:";
    for (const SceneFiles& f : s.scenes) o << " <a href=\"#scene-" << anchor(f.label) << "\">" << esc(f.label) << "</a>";
    if (!s.paper_tables.empty()) o << " <a href=\"#paper-tables\">Tables 1 and 2</a>";
    o << " <a href=\"#provenance\">provenance</a></nav>\n</header>\n";
    if (s.any_csv)
        o << "<p class=\"note\">Some tables of this folder have no structured twin (<code>*.table.toml</code>; the folder "
             "was written before they existed) and are read from their CSV, which keeps each number but not the "
             "Markdown's cell text: in those tables numbers show 4 significant digits and diverged cells cannot be "
             "marked. Their Markdown files (linked under each table) have the full text.</p>\n";
    o << "<section id=\"provenance\">\n<h2>Provenance</h2>\n" << provenance_html(s) << "</section>\n";
    for (const SceneFiles& f : s.scenes) o << scene_html(s, f);
    if (!s.paper_tables.empty()) {
        o << "<section id=\"paper-tables\">\n<h2>The paper's Tables 1 and 2</h2>\n";
        for (size_t i = 0; i < s.paper_tables.size(); ++i) o << table_html(s, s.paper_tables[i], "table-paper-" + std::to_string(i));
        o << "</section>\n";
    }
    if (!s.other_tables.empty() || !s.other_figures.empty() || !s.other_videos.empty()) {
        o << "<section id=\"other\">\n<h2>Other outputs</h2>\n";
        for (size_t i = 0; i < s.other_tables.size(); ++i) o << table_html(s, s.other_tables[i], "table-other-" + std::to_string(i));
        if (!s.other_figures.empty()) o << gallery_html(s.other_figures);
        for (const std::string& v : s.other_videos) o << video_html(v);
        o << "</section>\n";
    }
    o << "<footer><p class=\"files\">Page written by latentbench on " << esc(utc_now()) << ".</p></footer>\n";
    o << "<script>" << kScript << "</script>\n</body>\n</html>\n";
    return o.str();
}

} // namespace

std::string write_suite_page(const std::string& dir)
{
    const Suite s = scan(dir);
    const std::string path = (fs::path(dir) / "index.html").string();
    write_text_atomically(path, page_html(s));
    return path;
}

std::string write_suite_listing(const std::vector<std::string>& suite_dirs, const std::string& path)
{
    const fs::path base = fs::absolute(path).parent_path();
    std::ostringstream rows;
    for (const std::string& dir : suite_dirs) {
        if (!fs::exists(fs::path(dir) / "index.html"))
            throw IoError("'" + dir + "' has no index.html (write it first: latentbench page " + dir + ")");
        const Suite s = scan(dir);
        const std::string link = fs::relative(fs::absolute(fs::path(dir) / "index.html"), base).generic_string();
        rows << "<tr><td><a href=\"" << url(link) << "\">" << esc(s.name) << "</a></td><td>" << esc(s.description) << "</td><td>";
        for (size_t i = 0; i < s.scenes.size(); ++i) {
            rows << (i ? ", " : "") << "<a href=\"" << url(link) << "#scene-" << anchor(s.scenes[i].label) << "\">"
                 << esc(s.scenes[i].label) << "</a>";
        }
        rows << "</td><td>" << esc(fs::relative(fs::absolute(dir), base).generic_string()) << "</td></tr>\n";
    }
    std::ostringstream o;
    o << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>latentbench suites</title>\n<style>"
      << kStyle << "</style>\n</head>\n<body>\n<h1>latentbench suites</h1>\n"
      << "<p>One page per suite: its tables, figures, videos and provenance. Click a column header to sort.</p>\n"
      << "<div class=\"scroll\"><table class=\"sortable\" id=\"suites\"><thead><tr><th>suite</th><th>description</th>"
         "<th>scenes</th><th>folder</th></tr></thead>\n<tbody>\n"
      << rows.str() << "</tbody></table></div>\n<footer><p class=\"files\">Written by latentbench on " << esc(utc_now())
      << ".</p></footer>\n<script>" << kScript << "</script>\n</body>\n</html>\n";
    write_text_atomically(path, o.str());
    return path;
}

} // namespace lb
