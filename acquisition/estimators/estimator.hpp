#pragma once
// The impedance estimators (after libscopehal's AddDriverClass and libsigrok's
// driver list): one entry per estimator — its key, label, description, what it
// needs and gives, and the function that estimates — in one registry that the
// record-level dispatch (acquisition/impedance_assessment.cpp), the jobs, the
// CLI's choices and help, the GUI's curve styles and the docs' table read.
// Each estimator's entry is its own file in this folder (prony.cpp, fft.cpp,
// xspec.cpp, sine.cpp: the record-level glue around the dsp/ estimator);
// registry.cpp's register_builtin_estimators() lists them, one line each.
// How to add one: docs/extending.md.
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "acquisition/capture_calibration.hpp"
#include "acquisition/impedance_assessment.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::acq {

// What an estimator needs from a capture and what it gives (the CLI's help,
// the docs' table, and the dispatch's choices: which shots, averaged or not).
struct EstimatorCapabilities {
  bool transient_shots = false;  // needs transient (exp-decay, chirp) dut shots
  bool sine_shots = false;       // needs stepped-sine dut shots, one frequency each
  bool segments = false;         // takes every shot of the drive as a segment (not one averaged record)
  bool averages_shots = false;   // averages the shots of the drive sample by sample first
  bool sigma_per_point = false;  // gives σ of Z at every frequency
  bool modes = false;            // gives modes (poles) and a model order: order spread, stabilization chart
};

struct EstimateBand {
  double fmin_hz = 0, fmax_hz = 0, step_hz = 0;
};

// One estimate's input: the records (views; transient: one per shot of the
// drive, sine: one per frequency), the band and grid, the options.
struct EstimateInput {
  std::span<const dsp::DividerRecord> records;
  std::span<const double> frequencies_hz;  // sine shots: each record's drive frequency
  EstimateBand band;
  const AssessmentOptions& options;   // the estimators' own options: prony, fft, xspec, sine
  std::optional<std::size_t> order;      // a model order imposed (caps.modes); empty: the estimator's
  std::optional<std::size_t> bootstrap;  // the estimator's own bootstrap refits (caps.modes); empty: its options'
};

using EstimateFunction = std::function<dsp::ImpedanceResult(const EstimateInput&)>;

struct EstimatorEntry {
  std::string key;          // "prony": the CLI's --method value and the JSON's "method" stem
  std::string label;        // "Prony-SS": curves and tables
  std::string description;  // one line, for help texts and the docs' table
  EstimatorCapabilities caps;
  std::string sigma_source;  // where σ per point comes from, as the uncertainty band names it
  EstimateFunction estimate;
};

class EstimatorRegistry {
 public:
  // Throws std::invalid_argument on an empty or duplicate key, an empty label,
  // a missing function, or an entry that needs neither transient nor sine shots.
  void add(EstimatorEntry e);
  // nullptr for a key no entry has.
  const EstimatorEntry* find(const std::string& key) const;
  // Throws std::invalid_argument naming the key and the known ones.
  const EstimatorEntry& at(const std::string& key) const;
  const std::vector<EstimatorEntry>& entries() const { return entries_; }
  // The keys in registration order, of the entries `keep` accepts (all when empty).
  std::vector<std::string> keys(const std::function<bool(const EstimatorEntry&)>& keep = {}) const;

 private:
  std::vector<EstimatorEntry> entries_;
};

// prony, fft, xspec, sine (in this order: the CLI's choices and the docs' table).
void register_builtin_estimators(EstimatorRegistry& r);
// The registry filled by register_builtin_estimators() (built once, never changed).
const EstimatorRegistry& builtin_estimators();

// "prony, fft or xspec"; "a | b | c" with sep " | " and last " | ".
std::string join_keys(const std::vector<std::string>& keys, const std::string& sep = ", ",
                      const std::string& last = " or ");

// The docs' table of the estimators (acquisition/README.md, "The impedance estimators";
// tests/acquisition/test_estimators.cpp compares the two): key, label, what it
// needs, what it gives, the description.
std::string estimator_table_markdown(const EstimatorRegistry& r = builtin_estimators());

// The sample-by-sample mean of records of one drive (the first's rate, R1, pretrigger, ranges).
OwnedRecord mean_record(std::span<const dsp::DividerRecord> records);

}  // namespace piezo::acq
