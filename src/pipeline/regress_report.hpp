#pragma once
// What `latentbench regress` prints and writes: the Markdown diff (stdout) and JUnit
// XML for CI systems (one <testcase> per row of the report).
#include <string>

#include "pipeline/regress.hpp"

namespace lb {

/// GitHub-flavoured Markdown: a verdict line with the counts, the regressions and
/// missing rows named, then one table line per row and metric (baseline, now, change,
/// verdict and why). `run` and `baseline` are the folders compared (shown in the title).
std::string gate_markdown(const GateReport& report, const std::string& run, const std::string& baseline);

/// JUnit XML: one <testsuite> per scene, one <testcase> per row (classname
/// "regress.<scene>", name "<method>[ point] / <window>"); a regression is a
/// <failure> naming the metrics, a missing row a <failure> with fail_on_missing and
/// <skipped> otherwise, a new row passes with a note in <system-out>.
std::string gate_junit(const GateReport& report);

/// XML text escaping (& < > " ').
std::string xml_escape(const std::string& text);

} // namespace lb
