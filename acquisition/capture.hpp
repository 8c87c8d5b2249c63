#pragma once
// In-memory form of a piezo-capture/1 file (../shared/capture-format.md):
// the divider set-up and every shot. Pure data; HDF5 lives in capture_file.cpp.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "model/tube_geometry.hpp"

namespace piezo::acq {

inline constexpr std::string_view kFormatName = "piezo-capture";
inline constexpr std::int64_t kFormatVersion = 1;
inline constexpr std::size_t kMinSamples = 16;
// Plausibility limits of the reader (not of the format): a signal longer than
// kMaxSamples (1e8 samples, 0.8 GB per channel as float64) or a capture whose
// shots hold more than kMaxCaptureSamples per channel in all is refused before
// anything is allocated; a sample rate outside [kMinRateHz, kMaxRateHz] is
// refused (1/rate and N/rate must be ordinary finite numbers). A sample beyond
// kRangeMargin × the declared full scale (`v1_range_v`, `v2_range_v` or
// `daq_range_v`) cannot come from that converter: its over-range codes reach
// a few percent past full scale (an oscilloscope's ADC some 10-20 %, Infiniium:
// 8 divisions shown of about 10 digitised); 1.25 leaves room for all of them.
inline constexpr std::size_t kMaxSamples = 100'000'000;
inline constexpr std::size_t kMaxCaptureSamples = 400'000'000;
inline constexpr double kMinRateHz = 1.0, kMaxRateHz = 1e12;
inline constexpr double kRangeMargin = 1.25;

enum class Excitation { ExpDecay, Sine, Chirp, Noise, Arbitrary };
enum class Role { Dut, Open, Short, Load };

std::string_view to_string(Excitation e);
std::string_view to_string(Role r);
std::optional<Excitation> parse_excitation(std::string_view s);
std::optional<Role> parse_role(std::string_view s);

struct Setup {
  double divider_r1_ohm = 0.0;  // required, > 0
  std::optional<std::string> transducer_id;
  std::optional<double> inner_diameter_m, outer_diameter_m, length_m, density_kg_m3;
  std::optional<std::string> material;
  std::optional<std::string> notes;
  // An extension of piezo-capture/1 (readers ignore what they do not know):
  // this capture is the held-out partner of the capture of this file name in
  // the same folder (written by `measure`/`demo` for NAME-heldout.h5).
  std::optional<std::string> heldout_of;

  // The tube geometry with the project's defaults filled in where absent.
  model::TubeGeometry geometry() const;
};

struct Shot {
  double sample_rate_hz = 0.0;  // required, > 0
  Excitation excitation = Excitation::Arbitrary;
  std::optional<double> amplitude_v;
  std::optional<double> decay_per_s;  // exp_decay
  std::optional<double> frequency_hz;  // sine
  std::optional<double> f_start_hz, f_stop_hz;  // chirp
  std::int64_t pretrigger_samples = 0;
  Role role = Role::Dut;
  std::optional<double> load_ohm;  // role load
  std::optional<double> load_parallel_f;  // role load, default 0
  // Extension attribute `daq_range_v` (allowed by the format's "writers may
  // add attributes"): the DAQ's symmetric full scale, for exact clip flags.
  std::optional<double> daq_range_v;
  // Per-channel full scale and converter resolution, as other tools write them
  // (`v1_range_v`, `v2_range_v`, `adc_bits`); a channel's own range wins over
  // daq_range_v.
  std::optional<double> v1_range_v, v2_range_v;
  std::optional<std::int64_t> adc_bits;
  std::optional<double> range_v(int channel) const {
    const auto& own = channel == 1 ? v1_range_v : v2_range_v;
    return own ? own : daq_range_v;
  }
  std::vector<double> v1, v2;  // volts, same length N >= 16

  std::string name;  // "000003": set by the reader and the writer
  bool store_float32 = false;  // writer: store the signals as float32

  std::size_t samples() const { return v1.size(); }
};

struct Capture {
  std::string path;
  std::optional<std::string> created_utc;
  std::optional<std::string> software;
  Setup setup;
  std::vector<Shot> shots;
  // Lenient reads only: shots that were refused, one message each.
  std::vector<std::string> rejected_shots;
};

// A violation of the format: names the file, the path inside it and the problem.
class CaptureError : public std::runtime_error {
 public:
  CaptureError(std::string file, std::string h5path, std::string problem);
  const std::string& file() const { return file_; }
  const std::string& h5path() const { return h5path_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_, h5path_, problem_;
};

// Checks a shot against the writer's rules (also used before writing).
// Throws CaptureError with the given file name and the shot's path.
void validate_shot(const Shot& shot, const std::string& file, const std::string& h5path);
// The checks that need no samples (rate, length n, pretrigger, ranges): the
// reader runs them before it allocates anything.
void validate_shot_attributes(const Shot& shot, std::size_t n, const std::string& file,
                              const std::string& h5path);
void validate_setup(const Setup& setup, const std::string& file);

}  // namespace piezo::acq
