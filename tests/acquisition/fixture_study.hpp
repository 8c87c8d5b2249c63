#pragma once
// Test support for the fixture-compensation acceptance tests: the simulated
// bench with a fixture (lead resistance, fixture capacitance, R1 error, skew),
// a capture with open/short/load standards and dut shots, and the error
// metrics against the true transducer impedance away from its peaks.
#include <complex>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "acquisition/capture.hpp"
#include "acquisition/sim_setup.hpp"

namespace piezo::test {

struct FixtureSetting {
  const char* name;
  double cp_f, rs_ohm, r1_tolerance, skew_s;
};

// The seed's Table 4/5 tube (isotropic class), 0.5 % noise per channel, 14-bit DAQ.
acq::SimSpec fixture_spec(const FixtureSetting& s, std::uint64_t seed, double noise_rel = 0.005);

// The seed's lab drive (1 V exp_decay, 3000 1/s, 20000 samples at 10 MS/s),
// `shots` per standard and for the dut; standards open, short, load 1000 ohm
// when `calibrate`. Written to `file` and read back.
acq::Capture measure_capture(const acq::SimSpec& spec, int shots, bool calibrate,
                             const std::filesystem::path& file);

struct MaxError {
  double mag_pct = 0, mag_f_hz = 0;  // max | |Z|/|Z_true| − 1 | in %
  double phase_deg = 0, phase_f_hz = 0;
  std::size_t points = 0;
};

// Frequencies within ±1.5 % of a true resonance or anti-resonance ("the peaks").
std::vector<double> true_peaks(const std::function<std::complex<double>(double)>& truth,
                               double fmax_hz);
bool near_peak(double f, const std::vector<double>& peaks);

MaxError max_error(const std::vector<double>& f, const std::vector<std::complex<double>>& z,
                   const std::function<std::complex<double>(double)>& truth,
                   const std::vector<double>& peaks);

}  // namespace piezo::test
