#pragma once
// The fixture's physical quantities measured from the calibration standards:
// fixture capacitance (open), lead resistance (short), R1 error (load) and
// channel skew — what the gap diagnosis reports as MEASURED instead of
// leaving them aliased with the material (fixture capacitance looks like
// εT33, an R1 error like a joint scale of εT33 and d31).
//
// Model of a standard's measured divider transfer T_m = V2/V1 (the fixture of
// fixture_compensation.hpp; g the channel-2 gain, Rd the DAQ input, τ the skew):
//   T_m(ω) = e^{−jωτ} / (u + jωβ + ρ·R1_nom·Y_b(ω)),
//   u = (1 + R1/Rd)/(1 + g),   β = R1·Cp/(1 + g),   ρ = R1/((1 + g)·R1_nom),
//   Y_b = 0 (open), 1/Rs (short), 1/(Rs + Z_L(ω)) (load, Z_L = R_L ∥ C_L).
// The five real parameters (u, β, τ, ρ, Rs) are fitted by Levenberg–Marquardt
// to every frequency point of the standards present, weighted by their σ; then
//   fixture_capacitance = β/(ρ·R1_nom),  lead_resistance = Rs,
//   r1_error = ρ − 1 (R1 and the channel-2 gain act as one: R1/(1 + g)),
//   skew = τ,  open_dc_transfer = 1/u (1 for an ideal DAQ; R1/Rd and g act as one).
// A parameter the standards present cannot fix is held at its ideal value
// (u = 1, β = 0, ρ = 1, Rs = 0) and the assumption is listed.
#include <optional>
#include <string>
#include <vector>

#include "dsp/fixture_compensation.hpp"
#include "dsp/fixture_standards.hpp"

namespace piezo::dsp {

struct CalibrationStandards {
  std::optional<MeasuredStandard> open, shrt, load;  // Z_m with nominal R1, NOT deskewed
  LoadStandard load_value;
  double r1_nominal_ohm = 0.0;
  std::optional<double> skew_guess_s;  // start value (e.g. xcorr_delay of the short or load shot)
};

struct FixtureCalibration {
  std::optional<double> fixture_capacitance_f, lead_resistance_ohm, r1_error, skew_s,
      open_dc_transfer;
  std::optional<double> fixture_capacitance_sigma_f, lead_resistance_sigma_ohm, r1_error_sigma,
      skew_sigma_s, open_dc_transfer_sigma;
  double chi2_reduced =
      0.0;  // of the physical fit: ~1 when the fixture model explains the standards
  double residual_rel_rms = 0.0;  // rms |T_m − T_fit|/|T_fit|
  bool converged = false;
  int iterations = 0;
  std::vector<std::string> assumptions;  // parameters held at ideal values, and why
};

// Throws std::invalid_argument when no standard is given or the data are unusable.
FixtureCalibration fit_fixture(const CalibrationStandards& s);

}  // namespace piezo::dsp
