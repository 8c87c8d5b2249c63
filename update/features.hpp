#pragma once
// What the updater needs from a measured impedance function (seed §6.4.1):
// resonances (short-circuit modal frequencies), anti-resonances (open-circuit
// modal frequencies) and |Z| at one low frequency in the capacitive region.
// Filled explicitly, or from an impedance file (update/impedance_file.hpp);
// the capture → dsp pipeline fills the same struct.
#include <string>
#include <string_view>
#include <vector>

namespace piezo::update {

struct MeasuredFeatures {
  std::vector<double> resonances_hz;      // ascending, electrically active modes
  std::vector<double> antiresonances_hz;  // ascending
  double low_z_ohm = 0;                   // |Z(low_z_hz)|
  double low_z_hz = 0;
  // Optional 1-σ uncertainties (same length as the lists, or empty): weights
  // of the least-squares updater; CMCM does not use them.
  std::vector<double> resonance_sigma_hz, antiresonance_sigma_hz;
  double low_z_sigma_ohm = 0;

  // Throws std::invalid_argument("MeasuredFeatures::validate: …").
  void validate() const;
  // Capacitance implied by the low-frequency point, C = 1/(2π f_L |Z_L|) (eq. 199).
  double low_frequency_capacitance() const;
};

// "51400,55000,82600" → {51400, 55000, 82600}; throws std::invalid_argument.
std::vector<double> parse_list(std::string_view text);
// "26804@400" → {26804, 400} (ohm, Hz); throws std::invalid_argument.
std::pair<double, double> parse_ohm_at_hz(std::string_view text);

}  // namespace piezo::update
