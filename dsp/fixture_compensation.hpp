#pragma once
// Fixture compensation of a measured impedance from calibration standards
// (open, short, load) measured in the same fixture (Keysight, "Impedance
// Measurement Handbook", 6th ed., §4: open/short and open/short/load
// compensation).
//
// The bench's fixture, as the simulator builds it and the models below assume:
//
//   v1 ──[R1]──● v2 ──[Rs lead]──● terminals ── DUT ── GND
//              ├─ Cp (fixture, cable) ─ GND
//              └─ Rd (DAQ input) ─ GND
//   with the DAQ's channel-2 gain g and delay τ on v2.
//
// Whatever its elements, the measured Z_m = R1_nom·V2/(V1 − V2) is a bilinear
// (Möbius) function of the true Z_x at each frequency, so three known
// standards fix it completely:
//   open/short/load (exact for any such error box: R1 error, gain, skew too):
//     Z_x = Z_L · (Z_m − Z_s)(Z_o − Z_l) / ((Z_o − Z_m)(Z_l − Z_s))
//     (cross-ratio invariance; Z_o, Z_s, Z_l the measured standards, Z_L the
//     load's known value R_L/(1 + jωR_L·C_L));
//   open/short (shunt admittance at the v2 node, then the lead in series):
//     Y_o = 1/Z_o,  Z_lead = 1/(1/Z_s − Y_o),  Z_x = 1/(1/Z_m − Y_o) − Z_lead;
//   open only (shunt admittance): Z_x = 1/(1/Z_m − 1/Z_o);
//   short only (series impedance): Z_x = Z_m − Z_s.
// The partial models leave R1 error, channel gain and (unless deskewed first)
// skew in the result.
#include <complex>
#include <optional>
#include <string>
#include <string_view>

#include "dsp/fixture_standards.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

enum class FixtureModel { None, Open, Short, OpenShort, OpenShortLoad };

std::string_view to_string(
    FixtureModel m);  // "none", "open", "short", "open-short", "open-short-load"
std::optional<FixtureModel> parse_fixture_model(std::string_view s);
// One sentence: which model of the fixture the correction assumes.
std::string describe(FixtureModel m);

// The known value of the load standard: R ∥ C.
struct LoadStandard {
  double ohm = 0.0;
  double parallel_f = 0.0;
  std::complex<double> impedance(double f_hz) const;
};

class FixtureCompensation {
 public:
  // `model` must be supported by the standards given (throws std::invalid_argument
  // naming the missing standard); model None corrects nothing.
  FixtureCompensation(FixtureModel model, std::optional<StandardModel> open,
                      std::optional<StandardModel> shrt, std::optional<StandardModel> load,
                      LoadStandard load_value = {});

  // The most complete model the present standards support (None if none).
  static FixtureModel best_model(bool open, bool shrt, bool load);

  FixtureModel model() const { return model_; }
  std::complex<double> correct(double f_hz, std::complex<double> z_measured) const;
  // sqrt(E|δZ_x|²) at f from σ of the measured Z (sigma_measured, may be 0) and
  // from the standards' model uncertainty (first order, independent).
  double corrected_sigma(double f_hz, std::complex<double> z_measured, double sigma_measured) const;

  // Corrects Z (and z_sigma_ohm when present) of an estimate in place; features
  // are left to the caller (they move with the correction).
  void apply(ImpedanceResult& r) const;

 private:
  std::complex<double> correct_with(double f, std::complex<double> zm, std::complex<double> zo,
                                    std::complex<double> zs, std::complex<double> zl) const;
  FixtureModel model_;
  std::optional<StandardModel> open_, short_, load_;
  LoadStandard load_value_;
};

}  // namespace piezo::dsp
