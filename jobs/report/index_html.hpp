#pragma once
// The replay report's one page (issue 41 item 3): report/index.html, self-
// contained (the batch plots inline as SVG, no script, no external file), beside
// the Markdown: the lot's PASS/FAIL counts when limits were given, the
// distributions and histograms, and one row per capture — its PASS/FAIL with
// the reasons, the diagnosis' verdict, the constants (corrected ones labelled)
// with sigma and status, and links to its folder's page and plots.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace piezo::jobs::report {

// `records`: (key, replay record JSON) as in the results file. `report_dir`:
// where summary.md, distributions.svg, lot_histograms.svg and captures/ are.
std::string index_html(const std::vector<std::pair<std::string, nlohmann::json>>& records,
                       const std::string& results_file, const std::filesystem::path& report_dir);

// Writes report_dir/index.html; throws std::runtime_error naming the file it cannot write.
void write_index_html(const std::vector<std::pair<std::string, nlohmann::json>>& records,
                      const std::string& results_file, const std::filesystem::path& report_dir);

}  // namespace piezo::jobs::report
