#include "pipeline/regress_report.hpp"

#include <cstdio>
#include <map>
#include <sstream>
#include <vector>

namespace lb {

namespace {

std::string md_cell(const std::string& s)
{
    std::string out;
    for (char c : s) {
        if (c == '|') out += '\\';
        out += c == '\n' ? ' ' : c;
    }
    return out;
}

std::string tolerance_text(const GateOptions& o)
{
    std::string t;
    for (const GateMetric& m : o.metrics) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "%s %g %%", m.field.c_str(), m.relative * 100.0);
        std::string s = buf;
        if (m.absolute > 0.0) {
            std::snprintf(buf, sizeof buf, " + %g", m.absolute);
            s += buf;
        }
        if (m.higher_is_better) s += " (higher is better)";
        t += (t.empty() ? "" : "; ") + s;
    }
    return t;
}

/// The metrics of a row with a verdict other than unchanged, as one line.
std::string row_findings(const GateRowResult& r, GateVerdict which)
{
    std::string out;
    for (const GateMetricResult& m : r.metrics) {
        if (m.verdict != which) continue;
        out += (out.empty() ? "" : "; ") + m.field + " " + m.baseline + " -> " + m.now + " (" + m.reason + ")";
    }
    return out;
}

} // namespace

std::string xml_escape(const std::string& text)
{
    std::string out;
    for (char c : text) {
        switch (c) {
        case '&': out += "&amp;"; break;
        case '<': out += "&lt;"; break;
        case '>': out += "&gt;"; break;
        case '"': out += "&quot;"; break;
        case '\'': out += "&apos;"; break;
        default:
            // control characters other than tab and line breaks are not allowed in XML 1.0
            if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') out += ' ';
            else out += c;
        }
    }
    return out;
}

std::string gate_markdown(const GateReport& report, const std::string& run, const std::string& baseline)
{
    std::ostringstream out;
    const int reg = report.count(GateVerdict::Regression), imp = report.count(GateVerdict::Improvement),
              same = report.count(GateVerdict::Unchanged), miss = report.count(GateVerdict::Missing),
              added = report.count(GateVerdict::New);
    out << "# latentbench regress: " << run << " against " << baseline << "\n\n";
    out << "**" << (report.failed() ? "FAIL" : "PASS") << "**: " << reg << " regressed, " << imp << " improved, " << same
        << " unchanged, " << miss << " missing, " << added << " new (" << report.rows.size() << " rows).\n\n";
    out << "Tolerances (the baseline's seed range widened by): " << tolerance_text(report.options)
        << (report.options.check_divergence ? "; diverged seeds must not increase" : "") << ".\n\n";
    if (reg > 0) {
        out << "Regressions:\n\n";
        for (const GateRowResult& r : report.rows)
            if (r.verdict == GateVerdict::Regression) out << "- " << md_cell(r.key.text()) << ": " << md_cell(row_findings(r, GateVerdict::Regression)) << "\n";
        out << "\n";
    }
    if (miss > 0) {
        out << "Missing in the run (in the baseline only" << (report.options.fail_on_missing ? ", a failure" : ", reported only")
            << "):\n\n";
        for (const GateRowResult& r : report.rows)
            if (r.verdict == GateVerdict::Missing) out << "- " << md_cell(r.key.text()) << "\n";
        out << "\n";
    }
    if (added > 0) {
        out << "New in the run (not in the baseline):\n\n";
        for (const GateRowResult& r : report.rows)
            if (r.verdict == GateVerdict::New) out << "- " << md_cell(r.key.text()) << "\n";
        out << "\n";
    }
    out << "| scene | method | sweep point | window | metric | baseline | now | change | verdict |\n";
    out << "|---|---|---|---|---|--:|--:|--:|---|\n";
    for (const GateRowResult& r : report.rows) {
        const std::string prefix = "| " + md_cell(r.key.scene) + " | " + md_cell(r.key.method) + " | " +
                                   md_cell(r.key.point) + " | " + r.key.window + " | ";
        if (r.metrics.empty()) {
            out << prefix << "— | | | | " << to_string(r.verdict) << " |\n";
            continue;
        }
        for (const GateMetricResult& m : r.metrics) {
            out << prefix << m.field << " | " << md_cell(m.baseline) << " | " << md_cell(m.now) << " | " << md_cell(m.change)
                << " | " << to_string(m.verdict) << (m.reason.empty() ? "" : ": " + md_cell(m.reason)) << " |\n";
        }
    }
    return out.str();
}

std::string gate_junit(const GateReport& report)
{
    std::map<std::string, std::vector<const GateRowResult*>> by_scene;
    for (const GateRowResult& r : report.rows) by_scene[r.key.scene].push_back(&r);
    auto failed = [&](const GateRowResult& r) {
        return r.verdict == GateVerdict::Regression || (r.verdict == GateVerdict::Missing && report.options.fail_on_missing);
    };
    auto skipped = [&](const GateRowResult& r) { return r.verdict == GateVerdict::Missing && !report.options.fail_on_missing; };
    int failures = 0, skips = 0;
    for (const GateRowResult& r : report.rows) {
        failures += failed(r);
        skips += skipped(r);
    }
    std::ostringstream out;
    out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
    out << "<testsuites name=\"latentbench regress\" tests=\"" << report.rows.size() << "\" failures=\"" << failures
        << "\" errors=\"0\" skipped=\"" << skips << "\">\n";
    for (const auto& [scene, rows] : by_scene) {
        int f = 0, s = 0;
        for (const GateRowResult* r : rows) {
            f += failed(*r);
            s += skipped(*r);
        }
        out << "  <testsuite name=\"regress." << xml_escape(scene) << "\" tests=\"" << rows.size() << "\" failures=\"" << f
            << "\" errors=\"0\" skipped=\"" << s << "\">\n";
        for (const GateRowResult* r : rows) {
            const std::string name = r->key.method + (r->key.point.empty() ? "" : " [" + r->key.point + "]") + " / " + r->key.window;
            out << "    <testcase classname=\"regress." << xml_escape(scene) << "\" name=\"" << xml_escape(name) << "\">\n";
            std::string details;
            for (const GateMetricResult& m : r->metrics) {
                details += m.field + ": baseline " + m.baseline + ", now " + m.now + ", change " + m.change + ", " +
                           to_string(m.verdict) + (m.reason.empty() ? "" : " (" + m.reason + ")") + "\n";
            }
            if (r->verdict == GateVerdict::Regression) {
                out << "      <failure message=\"" << xml_escape(row_findings(*r, GateVerdict::Regression))
                    << "\" type=\"regression\">" << xml_escape(details) << "</failure>\n";
            } else if (r->verdict == GateVerdict::Missing) {
                const std::string message = "row in the baseline, missing in the run";
                if (report.options.fail_on_missing)
                    out << "      <failure message=\"" << message << "\" type=\"missing\"/>\n";
                else
                    out << "      <skipped message=\"" << message << "\"/>\n";
            } else if (r->verdict == GateVerdict::New) {
                details = "new row: not in the baseline\n";
            }
            if (!details.empty() && r->verdict != GateVerdict::Regression)
                out << "      <system-out>" << xml_escape(details) << "</system-out>\n";
            out << "    </testcase>\n";
        }
        out << "  </testsuite>\n";
    }
    out << "</testsuites>\n";
    return out.str();
}

} // namespace lb
