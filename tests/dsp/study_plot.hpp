#pragma once
// The chapter-5 comparison as a figure (test support): |Z| and phase over a log
// frequency axis (true vs each estimate), a linear zoom on the modes, and the
// |Z| error in dB against frequency (whole band and the modes' zoom) with the
// Cramér–Rao band and the ±1 dB target. Rows are drawn in the order given (put
// the smooth estimates last to keep them on top). Drawn by the project's
// Cairo plot renderer (jobs/report/plot_cairo).
#include <filesystem>
#include <string>
#include <vector>

#include "impedance_study.hpp"
#include "jobs/report/plot_cairo.hpp"

namespace piezo::study {

// A ±σ band drawn in the error panel (e.g. the CRB of 20·log10|Z| per frequency).
struct ErrorBand {
  std::string label;
  std::vector<double> f_hz, sigma_db;
  std::string colour = "#7f7f7f";
};

jobs::report::Figure comparison_figure(const StudyInput& in, const std::vector<StudyRow>& rows,
                                 const std::vector<ErrorBand>& bands, const std::string& title);

// Writes the figure; throws std::runtime_error naming the file when it cannot.
void write_comparison_svg(const jobs::report::Figure& fig, const std::filesystem::path& file);

}  // namespace piezo::study
