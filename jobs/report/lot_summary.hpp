#pragma once
// The lot summary of a replay with limits (limits.hpp): pass / fail / error
// counts; per limited quantity the distribution across the lot (n, mean,
// sample sd, min, max, median, MAD, a histogram), the robust outliers
// (modified z-score above Limits::outlier_z, report/robust_stats.hpp) and the
// process capability against the limits:
//   Cpu = (USL − μ)/(3σ),  Cpl = (μ − LSL)/(3σ),  Cpk = min(Cpu, Cpl),  Cp = (USL − LSL)/(6σ)
// with μ the mean and σ the sample standard deviation (n − 1) of the measured
// values; a one-sided limit has Cpu or Cpl only (and Cpk equal to it, said so
// by `one_sided`); σ = 0 or fewer than 2 values: no index. Quantities with an
// allowed list get counts per value instead. Pure computation; lot_report
// writes it out.
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "jobs/report/limits.hpp"
#include "jobs/report/robust_stats.hpp"

namespace piezo::jobs::report {

struct LotCapture {
  std::string path, key;
  CaptureVerdict verdict;
};

struct Histogram {
  double lo = 0, hi = 0;  // edges of the first and last bin
  std::vector<std::size_t> counts;
  double width() const {
    return counts.empty() ? 0.0 : (hi - lo) / static_cast<double>(counts.size());
  }
};

struct Capability {
  std::optional<double> cp, cpk, cpu, cpl;
  bool one_sided = false;
};

struct QuantitySummary {
  std::size_t limit = 0;  // index into Limits::limits
  // Numeric quantities: the measured values of the captures that were judged (not "error").
  std::vector<std::pair<std::size_t, double>> values;  // (capture index, value)
  std::size_t n = 0, not_measured = 0, below = 0, above = 0, not_allowed = 0;
  double mean = 0, sd = 0, min = 0, max = 0;
  RobustStats robust;
  Histogram histogram;
  std::vector<std::size_t> outliers;  // capture indices
  Capability capability;
  // Quantities with an allowed list: captures per value found (a string as
  // itself, a boolean as true / false).
  std::map<std::string, std::size_t> categories;
};

struct LotSummary {
  std::string limits_file, name;
  std::vector<LotCapture> captures;  // in path order
  std::size_t pass = 0, fail = 0, error = 0;
  std::vector<QuantitySummary> quantities;  // one per limit, in the file's order
};

// The sample mean and sd (n − 1) and the capability indices against a limit.
Capability capability(const Limit& l, double mean, double sd, std::size_t n);
// Bins over [lo, hi] (the data and the limits); a value on the top edge goes into the last bin.
Histogram histogram(const std::vector<double>& v, double lo, double hi, int bins);
// √n rounded up, clamped to 5..30.
int default_bins(std::size_t n);

struct LotRecord {
  std::string path, key;
  nlohmann::json record;  // a replay record (replay_record.hpp)
};
LotSummary summarize_lot(const Limits& l, std::vector<LotRecord> records);

nlohmann::json lot_json(const Limits& l, const LotSummary& s);

}  // namespace piezo::jobs::report
