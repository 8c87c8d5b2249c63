#pragma once
// Common input and result types of the impedance estimators (prony_ss, fft_ratio,
// cross_spectra, stepped_sine). The update/ layer and the CLI consume
// ImpedanceResult; nothing here knows about capture files.
#include <Eigen/Core>
#include <complex>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace piezo::dsp {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// One shot of the divider circuit  AWG ──[R1]──● v2 ── transducer ── GND,
// v1 on the generator side (capture-format.md): Z = V2/(V1 − V2)·R1 (seed eq. 170),
// current i = (v1 − v2)/R1. Sample `pretrigger_samples` is t = 0.
struct DividerRecord {
  std::span<const double> v1, v2;
  double sample_rate_hz = 0.0;
  double r1_ohm = 0.0;
  std::size_t pretrigger_samples = 0;
  std::optional<double> daq_range_v;  // for exact clip detection (channel 1, or both)
  std::optional<double> v2_range_v = std::nullopt;  // channel 2's own full scale, when it has one
  std::optional<double> range_v(int channel) const {
    return channel == 2 && v2_range_v ? v2_range_v : daq_range_v;
  }
};

// A frequency with its standard uncertainty (NaN when unknown).
// For Prony estimates f_hz is the natural frequency |s*|/2π of the zero (for a
// resonance) or pole (anti-resonance) of Z(s) found next to the |Z| extremum —
// the short-/open-circuit modal frequency, free of the damping bias of the
// extremum; extremum_hz is where |Z(jω)| peaks. Estimators without a pole
// model report the extremum in both.
struct Feature {
  double f_hz = kNaN;
  double sigma_hz = kNaN;
  double extremum_hz = kNaN;
  double damping_ratio = kNaN;  // of that zero / pole (Prony only)
};

struct ImpedanceFeatures {
  std::vector<Feature> resonances;      // local minima of |Z|
  std::vector<Feature> antiresonances;  // local maxima of |Z|
  double capacitance_f = kNaN;          // low-frequency capacitance Im(1/Z)/ω
  double capacitance_sigma_f = kNaN;
};

// A pole λ = −a + jω of the signal model (eq. 164) with f = ω/2π and
// damping ratio ξ = a/|λ| (eq. 165).
struct PoleInfo {
  std::complex<double> lambda;
  double freq_hz = 0.0;
  double damping_ratio = 0.0;
};

struct PronySummary {
  std::size_t order = 0;
  bool order_automatic = true;
  std::vector<double> singular_values_normalized;  // s_k / s_1, as computed
  std::vector<PoleInfo> poles;                      // global poles, Im λ ≥ 0 only
};

struct ImpedanceResult {
  std::string method;                // "prony", "fft", "xspec-h1", "sine", ...
  Eigen::VectorXd f_hz;
  Eigen::VectorXcd z_ohm;
  Eigen::VectorXd z_sigma_ohm;       // per-point sqrt(E|δZ|²); empty when unknown
  Eigen::VectorXd coherence;         // cross-spectra only; empty otherwise
  ImpedanceFeatures features;
  std::optional<PronySummary> prony;
  std::size_t samples_used = 0;      // samples per channel that entered the estimate
};

// The frequency grid fmin, fmin+step, … ≤ fmax (validated).
Eigen::VectorXd make_grid(double fmin_hz, double fmax_hz, double step_hz);

}  // namespace piezo::dsp
