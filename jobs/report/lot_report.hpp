#pragma once
// The lot report of a replay with limits: lot.md (counts, a table per
// quantity with n, mean, sd, min, max, Cp/Cpk, outliers; the failed captures
// with their reasons), lot.json (lot_json of lot_summary.hpp) and the
// histograms of the limited quantities with the limits drawn, as
// lot_histograms.svg and lot_histograms.png, in the replay's report folder.
#include <filesystem>
#include <string>

#include "jobs/report/limits.hpp"
#include "jobs/report/lot_summary.hpp"
#include "jobs/report/plot_cairo.hpp"

namespace piezo::jobs::report {

std::string lot_markdown(const Limits& l, const LotSummary& s, const std::string& results_file);
// One panel per numeric limit: the histogram (count per bin, outlined), the
// limits as dashed red lines, the mean as a grey line, the robust outliers as red points.
Figure lot_figure(const Limits& l, const LotSummary& s);
// Writes DIR/lot.md, lot.json, lot_histograms.svg and .png; throws naming a file it cannot write.
void write_lot_report(const Limits& l, const LotSummary& s, const std::string& results_file,
                      const std::filesystem::path& dir);

}  // namespace piezo::jobs::report
