#pragma once
// A measurement plan: what the AWG plays, how the DAQ records, how many shots.
// Plans come from CLI options or TOML files (see fixtures/plans/*.toml).
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/capture.hpp"

namespace piezo::acq {

struct ExcitationSpec {
  Excitation kind = Excitation::ExpDecay;
  double amplitude_v = 1.0;  // peak
  double decay_per_s = 3000.0;  // exp_decay (seed §5.2 lab test)
  double frequency_hz = 50e3;  // sine (one step)
  double f_start_hz = 1e3, f_stop_hz = 120e3;  // chirp; stepped sine range
  double f_step_hz = 0.0;  // stepped sine: > 0 makes one shot per frequency
  std::uint64_t noise_seed = 1;  // noise excitation
  // chirp / noise: the burst fills this fraction of the post-trigger record,
  // then the output rests, so the transducer rings down inside the record
  // (a burst cut by the record's end biases every FFT-based estimate).
  double burst_fraction = 1.0;
};

struct MeasurementPlan {
  // Plausibility limits (not of the instruments): a plan beyond them is a
  // typo, and would otherwise allocate or loop without bound. kMaxSamples is
  // the capture reader's limit per signal; kMaxShots bounds steps × shots.
  static constexpr std::size_t kMaxSamples = 100'000'000;
  static constexpr std::size_t kMaxSteps = 100'000;
  static constexpr int kMaxShots = 1'000'000;

  ExcitationSpec excitation;
  double sample_rate_hz = 1e7;
  std::size_t samples = 20000;  // record length per shot
  std::size_t pretrigger_samples = 200;
  int shots = 1;  // repeats of each excitation step
  double range_v = 0.0;  // DAQ ±range per channel; 0 = 1.25 × amplitude
  Setup setup;  // R1, transducer id, geometry, material

  void validate() const;  // throws std::invalid_argument naming the field
  // The excitation steps: one for exp_decay/chirp/noise/sine, several for a stepped sine.
  std::vector<ExcitationSpec> steps() const;
  double daq_range_v() const;
};

// Reads a TOML plan; unknown keys are errors (a typo must not pass silently).
// Throws std::invalid_argument naming the file and the key.
MeasurementPlan load_plan_toml(const std::filesystem::path& file);
// The same from TOML text; `source` names it in messages (and in TOML errors).
MeasurementPlan parse_plan_toml(std::string_view toml_text, const std::string& source = "<string>");

// The AWG samples for one step, normalised to [-1, 1], at the plan's rate,
// covering the post-trigger part of the record.
std::vector<double> synthesize(const ExcitationSpec& e, double sample_rate_hz, std::size_t n);

}  // namespace piezo::acq
