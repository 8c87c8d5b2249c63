#pragma once
// The batch summary of a replay: parameter and feature distributions across
// transducers (median, MAD, range), outliers flagged by the modified z-score
// (report/robust_stats.hpp), failed captures listed. Written as summary.md and
// distributions.svg beside the per-capture report folders.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "jobs/report/robust_stats.hpp"
#include "jobs/report/plot_cairo.hpp"

namespace piezo::jobs::report {

struct BatchEntry {
  std::string key, path, sha256, status;  // status "ok" | "failed"
  std::string error;                      // failed: the message
  std::string verdict;
  struct Value {
    std::string name, unit;
    double value = 0;
  };
  // Updated parameters in the pipeline's order, then fs_mode1..3, fp_mode1..3
  // (Hz; the per-mode figures' modes), or f_r1..3, f_a1..3 "(estimate order)" without them.
  std::vector<Value> values;
  const Value* find(const std::string& name) const;
};

// From a replay record (the JSON object of one line of the JSONL output:
// path, sha256, status, and result or error).
BatchEntry batch_entry(const std::string& key, const nlohmann::json& record);

struct Distribution {
  std::string name, unit;
  RobustStats stats;
  std::vector<std::pair<std::size_t, double>> values;  // (entry index, value)
  std::vector<std::size_t> outliers;                   // entry indices
};

struct BatchSummary {
  std::vector<BatchEntry> entries;  // sorted by path
  std::vector<Distribution> distributions;
  std::size_t ok = 0, failed = 0;
};

BatchSummary summarize(std::vector<BatchEntry> entries);

// The per-capture report folder of an entry, relative to the report folder.
std::string capture_report_folder(const std::string& path, const std::string& key);

std::string batch_summary_markdown(const BatchSummary& s, const std::string& results_file);
Figure distributions_figure(const BatchSummary& s);
// Writes DIR/summary.md and DIR/distributions.svg; throws naming a file it cannot write.
void write_batch_report(const BatchSummary& s, const std::string& results_file,
                        const std::filesystem::path& dir);

}  // namespace piezo::jobs::report
