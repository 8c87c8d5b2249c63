#pragma once
// The per-capture report of a replay, one folder per capture:
//   summary.md      what was replayed, stages, parameters, features, warnings
//   impedance.svg   |Z| and phase overlays (report/impedance_plot.hpp)
//   impedance.csv   the measured impedance, f_hz,re_ohm,im_ohm
//   impedance.s1p   the same as Touchstone 1-port (Z, RI)
//   result.json     the JSON report: parameters, features, stages, warnings
// A capture that failed gets a summary.md with the error only.
#include <filesystem>
#include <string>
#include <vector>

#include "jobs/pipeline/pipeline.hpp"

namespace piezo::jobs::report {

struct CaptureInfo {
  std::string input_path, sha256;
  std::string material;  // the nominal model that was updated
  double elapsed_s = 0;
  // With acceptance limits: "PASS" / "FAIL" and the failed checks' reasons,
  // shown at the top of the capture's page (empty: no limits loaded).
  std::string limits_status;
  std::vector<std::string> limits_reasons;
};

std::string capture_summary_markdown(const jobs::PipelineResult& r, const CaptureInfo& info);
std::string failed_capture_markdown(const CaptureInfo& info, const std::string& error);

// Creates `dir` and writes the files above. Throws std::runtime_error naming a
// file that cannot be written.
void write_capture_report(const jobs::PipelineResult& r, const CaptureInfo& info,
                          const std::filesystem::path& dir);
void write_failed_capture_report(const CaptureInfo& info, const std::string& error,
                                 const std::filesystem::path& dir);

}  // namespace piezo::jobs::report
