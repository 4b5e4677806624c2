#include "pipeline/regress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <set>
#include <tuple>

#include "core/error.hpp"
#include "eval/summary_schema.hpp"
#include "io/table.hpp"
#include "io/toml_config.hpp"

namespace fs = std::filesystem;

namespace lb {

namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// Metrics a tolerance file may gate, and their direction: the horizons (higher is
/// better) and the errors aggregated before the stable horizon (lower is better).
/// Times are not gated (performance is report-only: `scripts/run bench --compare`).
const std::map<std::string, bool>& gateable_metrics()
{
    static const std::map<std::string, bool> m = {
        {"stable_horizon", true}, {"horizon_loose", true},     {"horizon_tight", true}, {"final_rmse", false},
        {"mean_rmse", false},     {"max_bc_violation", false}, {"ke_ratio", false},     {"mean_residual", false},
        {"sted", false}};
    return m;
}

const SummaryMetric* metric_by_field(const std::string& field)
{
    for (const SummaryMetric& m : summary_metrics())
        if (field == m.field) return &m;
    return nullptr;
}

/// Combine one seed's sequences as the methods tables do (the metric's aggregation).
double aggregate_values(const std::vector<double>& v, SummaryAggregation how)
{
    std::vector<double> finite;
    for (double x : v)
        if (std::isfinite(x)) finite.push_back(x);
    switch (how) {
    case SummaryAggregation::Sum: {
        double s = 0.0;
        for (double x : v) s += x;
        return s;
    }
    case SummaryAggregation::Min: {
        double s = std::numeric_limits<double>::infinity();
        for (double x : v) s = std::min(s, x);
        return v.empty() ? kNan : s;
    }
    case SummaryAggregation::Max:
        return finite.empty() ? kNan : *std::max_element(finite.begin(), finite.end());
    case SummaryAggregation::Mean:
    default: {
        if (finite.empty()) return kNan;
        double s = 0.0;
        for (double x : finite) s += x;
        return s / double(finite.size());
    }
    }
}

size_t column_index(const Table& t, const std::string& name, const std::string& source, bool required)
{
    const auto it = std::find(t.columns.begin(), t.columns.end(), name);
    if (it == t.columns.end()) {
        if (required) throw IoError(source + ": no column '" + name + "' (not a table written by latentbench run?)");
        return std::string::npos;
    }
    return size_t(it - t.columns.begin());
}

double cell_value(const TableCell& c) { return c.value ? *c.value : kNan; }

/// "train (frames 2-299)" -> "train".
std::string window_word(const std::string& text, const std::string& where)
{
    const std::string w = text.substr(0, text.find(' '));
    if (w != "train" && w != "test") throw IoError(where + ": window '" + text + "' is neither train nor test");
    return w;
}

/// rollouts_<scene>.csv (observations_ in older runs): group by row key, then by seed, aggregate over sequences.
std::vector<GateRow> rows_from_observations(const std::string& path)
{
    const Table t = read_csv(path);
    const size_t scene = column_index(t, "scene", path, true), method = column_index(t, "method", path, true),
                 point = column_index(t, "sweep point", path, true), seed = column_index(t, "seed", path, true),
                 window = column_index(t, "window", path, true), diverged = column_index(t, "diverged", path, true);
    std::vector<std::pair<std::string, size_t>> fields;  // gateable metric -> column
    for (const auto& [field, higher] : gateable_metrics()) {
        (void)higher;
        const size_t c = column_index(t, field, path, false);
        if (c != std::string::npos) fields.emplace_back(field, c);
    }
    // key -> seed text -> per field the sequences' values; and the diverged flags
    std::map<GateRowKey, std::map<std::string, std::map<std::string, std::vector<double>>>> grouped;
    std::map<GateRowKey, std::map<std::string, bool>> seed_diverged;
    for (size_t r = 0; r < t.rows.size(); ++r) {
        const auto& row = t.rows[r];
        const std::string where = path + ": row " + std::to_string(r + 1);
        GateRowKey key{row[scene].text, row[method].text, row[point].text, window_word(row[window].text, where)};
        if (key.scene.empty() || key.method.empty()) throw IoError(where + ": empty scene or method");
        const std::string seed_text = row[seed].text;
        auto& per_field = grouped[key][seed_text];
        for (const auto& [field, c] : fields) per_field[field].push_back(cell_value(row[c]));
        const double d = cell_value(row[diverged]);
        if (!(d == 0.0 || d == 1.0)) throw IoError(where + ": diverged is '" + row[diverged].text + "', not 0 or 1");
        seed_diverged[key][seed_text] = seed_diverged[key][seed_text] || d == 1.0;
    }
    std::vector<GateRow> out;
    for (const auto& [key, seeds] : grouped) {
        GateRow g;
        g.key = key;
        g.source = path;
        g.seeds = int(seeds.size());
        for (const auto& [seed_text, per_field] : seeds) {
            g.diverged += seed_diverged[key][seed_text] ? 1 : 0;
            for (const auto& [field, values] : per_field)
                g.values[field].push_back(aggregate_values(values, metric_by_field(field)->aggregation));
        }
        out.push_back(std::move(g));
    }
    return out;
}

/// methods_<scene>.csv (a folder without rollouts_/observations_ tables): one observation
/// per table row. Today's CSV (the Markdown's machine-readable twin) gives each metric's
/// median over the row's seeds (`<field>_median`) and the seed and divergence counts; an
/// older one the metrics under their column titles (the schema's), divergence unknown.
std::vector<GateRow> rows_from_methods_table(const std::string& path, const std::string& scene)
{
    const Table t = read_csv(path);
    const size_t method = column_index(t, "method", path, true), window = column_index(t, "window", path, true);
    const size_t point = column_index(t, "sweep point", path, false);
    const size_t n_seeds = column_index(t, "n_seeds", path, false), n_diverged = column_index(t, "n_diverged", path, false);
    const bool twin = n_seeds != std::string::npos && n_diverged != std::string::npos;
    std::vector<std::pair<std::string, size_t>> fields;
    for (const auto& [field, higher] : gateable_metrics()) {
        (void)higher;
        const SummaryMetric* m = metric_by_field(field);
        const std::string percent = m->title[0] == '%' ? "_percent" : "";
        const size_t c = twin ? column_index(t, field + percent + "_median", path, false) : column_index(t, m->title, path, false);
        if (c != std::string::npos) fields.emplace_back(field, c);
    }
    std::vector<GateRow> out;
    for (size_t r = 0; r < t.rows.size(); ++r) {
        const auto& row = t.rows[r];
        const std::string where = path + ": row " + std::to_string(r + 1);
        GateRow g;
        g.key = {scene, row[method].text, point == std::string::npos ? "" : row[point].text,
                 window_word(row[window].text, where)};
        g.source = path;
        g.seeds = twin ? int(cell_value(row[n_seeds])) : 1;
        g.diverged = twin ? int(cell_value(row[n_diverged])) : -1;  // an old CSV: the stable horizon, not the frame count
        for (const auto& [field, c] : fields) {
            // A percentage column holds percent; the gate compares the schema's fractions.
            const double v = cell_value(row[c]);
            g.values[field].push_back(twin && metric_by_field(field)->title[0] == '%' ? v / 100.0 : v);
        }
        out.push_back(std::move(g));
    }
    return out;
}

struct Stats {
    double lo = kNan, hi = kNan, median = kNan;
    int finite = 0, total = 0;
};

Stats stats_of(const std::vector<double>& v)
{
    Stats s;
    s.total = int(v.size());
    std::vector<double> f;
    for (double x : v)
        if (std::isfinite(x)) f.push_back(x);
    s.finite = int(f.size());
    if (f.empty()) return s;
    std::sort(f.begin(), f.end());
    s.lo = f.front();
    s.hi = f.back();
    const size_t n = f.size();
    s.median = n % 2 ? f[n / 2] : 0.5 * (f[n / 2 - 1] + f[n / 2]);
    return s;
}

std::string number_text(double v, bool integer)
{
    if (std::isnan(v)) return "nan";
    char buf[64];
    if (integer) std::snprintf(buf, sizeof buf, "%.0f", v);
    else std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

std::string stats_text(const Stats& s, bool integer)
{
    if (s.finite == 0) return s.total > 1 ? "nan (" + std::to_string(s.total) + " seeds)" : "nan";
    if (s.total == 1) return number_text(s.median, integer);
    std::string t = number_text(s.median, integer) + " [" + number_text(s.lo, integer) + ", " + number_text(s.hi, integer) +
                    "] (" + std::to_string(s.total) + " seeds";
    if (s.finite < s.total) t += ", " + std::to_string(s.total - s.finite) + " nan";
    return t + ")";
}

GateMetricResult compare_metric(const GateMetric& m, const std::vector<double>& base, const std::vector<double>& now)
{
    const SummaryMetric* schema = metric_by_field(m.field);
    const bool integer = schema && schema->integer;
    const Stats b = stats_of(base), n = stats_of(now);
    GateMetricResult r;
    r.field = m.field;
    r.baseline = stats_text(b, integer);
    r.now = stats_text(n, integer);
    if (b.finite == 0 && n.finite == 0) {
        r.change = "—";
        return r;
    }
    if (b.finite == 0) {
        r.change = "nan -> finite";
        r.verdict = GateVerdict::Improvement;
        r.reason = "the baseline had no value (no frames before its blow-up)";
        return r;
    }
    if (n.finite == 0) {
        r.change = "finite -> nan";
        r.verdict = GateVerdict::Regression;
        r.reason = "no value any more (no frames before the blow-up)";
        return r;
    }
    const double bottom = b.lo - (std::abs(b.lo) * m.relative + m.absolute);
    const double top = b.hi + (std::abs(b.hi) * m.relative + m.absolute);
    if (integer) {
        const double d = n.median - b.median;
        r.change = (d > 0 ? "+" : "") + number_text(d, true) + " frames";
    } else if (b.median != 0.0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%+.1f %%", 100.0 * (n.median / b.median - 1.0));
        r.change = buf;
    } else {
        r.change = n.median == 0.0 ? "+0.0 %" : "from 0";
    }
    const bool above = n.median > top, below = n.median < bottom;
    if (!above && !below) return r;
    const bool worse = m.higher_is_better ? below : above;
    r.verdict = worse ? GateVerdict::Regression : GateVerdict::Improvement;
    r.reason = std::string(above ? "above the band's top " : "below the band's bottom ") +
               number_text(above ? top : bottom, false) + " (baseline " + (above ? "max " : "min ") +
               number_text(above ? b.hi : b.lo, integer) + (above ? " + " : " - ") + number_text(m.relative * 100.0, false) +
               " %" + (m.absolute > 0.0 ? " + " + number_text(m.absolute, false) : std::string()) + ")";
    return r;
}

int severity(GateVerdict v)
{
    switch (v) {
    case GateVerdict::Regression: return 3;
    case GateVerdict::Improvement: return 1;
    default: return 0;
    }
}

} // namespace

std::vector<GateMetric> default_gate_metrics()
{
    return {
        {"stable_horizon", true, 0.0, 0.0},
        {"horizon_loose", true, 0.1, 0.0},
        {"mean_rmse", false, 0.25, 1e-4},
        {"final_rmse", false, 0.5, 1e-4},
        {"max_bc_violation", false, 0.5, 1e-4},
    };
}

GateOptions default_gate_options()
{
    GateOptions o;
    o.metrics = default_gate_metrics();
    return o;
}

GateOptions load_gate_options(const std::string& path)
{
    GateOptions o = default_gate_options();
    const toml::table root = parse_toml_file(path);
    ConfigTable cfg(root, "", path);
    o.fail_on_missing = cfg.get_bool("fail_on_missing", o.fail_on_missing);
    o.check_divergence = cfg.get_bool("check_divergence", o.check_divergence);
    if (const toml::table* metrics = cfg.raw_table("metrics")) {
        std::optional<ConfigTable> mt = cfg.table("metrics");
        for (const auto& [name, node] : *metrics) {
            const std::string field(name.str());
            const auto known = gateable_metrics().find(field);
            if (known == gateable_metrics().end()) {
                std::string list;
                for (const auto& [f, h] : gateable_metrics()) list += (list.empty() ? "" : ", ") + f;
                mt->fail(field, "is not a metric the gate can check (one of: " + list + ")");
            }
            ConfigTable t = mt->require_table(field);
            auto it = std::find_if(o.metrics.begin(), o.metrics.end(), [&](const GateMetric& g) { return g.field == field; });
            GateMetric m = it != o.metrics.end() ? *it : GateMetric{field, known->second, 0.0, 0.0};
            m.relative = t.get_double("relative", m.relative);
            m.absolute = t.get_double("absolute", m.absolute);
            if (!(m.relative >= 0.0)) t.fail("relative", "must be >= 0 (a fraction: 0.25 widens the range by 25 %)");
            if (!(m.absolute >= 0.0)) t.fail("absolute", "must be >= 0 (in the metric's unit)");
            const bool gate = t.get_bool("gate", true);
            t.finish();
            if (it != o.metrics.end() && gate) *it = m;  // keeps the defaults' order
            else if (it != o.metrics.end()) o.metrics.erase(it);
            else if (gate) o.metrics.push_back(m);
        }
        mt->finish();
    }
    cfg.finish();
    return o;
}

bool GateRowKey::operator<(const GateRowKey& o) const
{
    // train before test within a row pair
    return std::tie(scene, method, point, window) < std::tie(o.scene, o.method, o.point, o.window);
}

bool GateRowKey::operator==(const GateRowKey& o) const
{
    return scene == o.scene && method == o.method && point == o.point && window == o.window;
}

std::string GateRowKey::text() const
{
    return scene + " / " + method + (point.empty() ? "" : " [" + point + "]") + " / " + window;
}

std::vector<GateRow> load_gate_rows(const std::string& dir)
{
    if (!fs::is_directory(dir)) throw IoError(dir + ": no such directory (a run directory or a results/ folder)");
    const std::string tables = fs::is_directory(fs::path(dir) / "tables") ? (fs::path(dir) / "tables").string() : dir;
    std::map<std::string, std::string> observations, methods;  // scene -> file
    for (const auto& e : fs::directory_iterator(tables)) {
        if (e.path().extension() != ".csv") continue;
        const std::string stem = e.path().stem().string();
        // rollouts_<scene>.csv; observations_<scene>.csv is its name in runs before 2026-12-05.
        if (stem.rfind("rollouts_", 0) == 0) observations[stem.substr(9)] = e.path().string();
        else if (stem.rfind("observations_", 0) == 0) observations.emplace(stem.substr(13), e.path().string());
        else if (stem.rfind("methods_", 0) == 0) methods[stem.substr(8)] = e.path().string();
    }
    if (observations.empty() && methods.empty())
        throw IoError(tables + ": no rollouts_*.csv nor methods_*.csv (has the run finished its tables stage?)");
    std::vector<GateRow> rows;
    for (const auto& [scene, file] : observations) {
        for (GateRow& r : rows_from_observations(file)) rows.push_back(std::move(r));
    }
    for (const auto& [scene, file] : methods) {
        if (observations.count(scene)) continue;
        for (GateRow& r : rows_from_methods_table(file, scene)) rows.push_back(std::move(r));
    }
    std::sort(rows.begin(), rows.end(), [](const GateRow& a, const GateRow& b) { return a.key < b.key; });
    for (size_t k = 1; k < rows.size(); ++k) {
        if (rows[k].key == rows[k - 1].key)
            throw IoError(rows[k].source + ": row " + rows[k].key.text() + " appears twice (also in " + rows[k - 1].source + ")");
    }
    return rows;
}

const char* to_string(GateVerdict v)
{
    switch (v) {
    case GateVerdict::Unchanged: return "unchanged";
    case GateVerdict::Improvement: return "improvement";
    case GateVerdict::Regression: return "REGRESSION";
    case GateVerdict::Missing: return "missing";
    case GateVerdict::New: return "new";
    }
    return "?";
}

int GateReport::count(GateVerdict v) const
{
    return int(std::count_if(rows.begin(), rows.end(), [v](const GateRowResult& r) { return r.verdict == v; }));
}

bool GateReport::failed() const
{
    return count(GateVerdict::Regression) > 0 || (options.fail_on_missing && count(GateVerdict::Missing) > 0);
}

GateReport compare_gate_rows(const std::vector<GateRow>& baseline, const std::vector<GateRow>& now,
                             const GateOptions& options)
{
    GateReport report;
    report.options = options;
    std::map<GateRowKey, const GateRow*> b, n;
    for (const GateRow& r : baseline) b[r.key] = &r;
    for (const GateRow& r : now) n[r.key] = &r;
    std::set<GateRowKey> keys;
    for (const auto& [k, r] : b) keys.insert(k);
    for (const auto& [k, r] : n) keys.insert(k);
    for (const GateRowKey& key : keys) {
        GateRowResult row;
        row.key = key;
        const auto bi = b.find(key), ni = n.find(key);
        if (ni == n.end()) {
            row.verdict = GateVerdict::Missing;
        } else if (bi == b.end()) {
            row.verdict = GateVerdict::New;
        } else {
            const GateRow& base = *bi->second;
            const GateRow& cur = *ni->second;
            if (options.check_divergence && base.diverged >= 0 && cur.diverged >= 0) {
                GateMetricResult d;
                d.field = "diverged";
                d.baseline = std::to_string(base.diverged) + "/" + std::to_string(base.seeds) + " seeds";
                d.now = std::to_string(cur.diverged) + "/" + std::to_string(cur.seeds) + " seeds";
                const double fb = double(base.diverged) / std::max(base.seeds, 1);
                const double fn = double(cur.diverged) / std::max(cur.seeds, 1);
                d.change = fn == fb ? "—" : d.baseline + " -> " + d.now;
                if (fn > fb) {
                    d.verdict = GateVerdict::Regression;
                    d.reason = base.diverged == 0 ? "newly diverged" : "more seeds diverged";
                } else if (fn < fb) {
                    d.verdict = GateVerdict::Improvement;
                    d.reason = cur.diverged == 0 ? "no longer diverges" : "fewer seeds diverged";
                }
                row.metrics.push_back(d);
            }
            for (const GateMetric& m : options.metrics) {
                const auto vb = base.values.find(m.field), vn = cur.values.find(m.field);
                if (vb == base.values.end() || vn == cur.values.end()) continue;
                row.metrics.push_back(compare_metric(m, vb->second, vn->second));
            }
            for (const GateMetricResult& m : row.metrics) {
                if (severity(m.verdict) > severity(row.verdict)) row.verdict = m.verdict;
            }
        }
        report.rows.push_back(std::move(row));
    }
    return report;
}

} // namespace lb
