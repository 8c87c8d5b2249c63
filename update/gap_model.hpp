#pragma once
// The model the gap diagnosis fits to a measured impedance: the FE tube
// (four material parameters of the updated class), Rayleigh damping and any
// subset of the effect catalogue, through the bench's frequency-domain twin
// (model/bench_response.hpp). Parameters live in scaled coordinates x so that
// one unit is a comparable, physically small change:
//   material  x = ln(p / p_ref) / 0.01        (1 % per unit; d31 by its magnitude)
//   damping   x = ξ contribution at f_ref / 0.001: α/(2ω_ref), β·ω_ref/2
//   effect    x = value / its typical magnitude (daq_input_resistance as a conductance)
//
// Re-solving the FE modes for every trial would make a fit cost seconds, so
// the port model (C0, C_res, per mode ω_k, p_k², κ_k) is linearised in the
// four material coordinates — and the end-mass fraction when mass_loading is
// a parameter — around a reference point, and re-linearised by the fitter when
// it moves away (GapModel::relinearise).
#include <complex>
#include <memory>
#include <string>
#include <vector>

#include "model/effects.hpp"
#include "model/modal.hpp"
#include "model/port_model.hpp"
#include "update/parametrization.hpp"

namespace piezo::update {

enum class GapParam { y_e11, nu12, d31, eps_t33, damping_alpha, damping_beta, effect };

struct GapParamInfo {
  GapParam kind;
  std::string name;           // "YE11", …, "rayleigh_alpha", "rayleigh_beta", or the effect's catalogue name
  const model::EffectInfo* effect = nullptr;
  double lower = 0, upper = 0;  // bounds in x
};

class GapModel {
 public:
  // `solver` must outlive the model. `damping_ref_hz`: where the damping
  // coordinates are expressed (e.g. the first resonance).
  GapModel(model::ModalSolver& solver, MaterialClass cls, TubeParams p_ref, model::RayleighDamping damping,
           double r1_nominal_ohm, double damping_ref_hz, int n_modes = 20);

  // The parameter list: the four material parameters, α, β, then `effects` (by catalogue name).
  void set_effects(const std::vector<std::string>& effects);
  // Effects known from elsewhere (the fixture calibration's measured Cp, lead
  // R, R1 error, skew): always in the model at these values, never fitted.
  // An effect that is also a fitted parameter takes the fitted value.
  void set_fixed_effects(const model::EffectSet& e) { fixed_ = e; }
  const model::EffectSet& fixed_effects() const { return fixed_; }
  const std::vector<GapParamInfo>& params() const { return params_; }
  int size() const { return static_cast<int>(params_.size()); }

  // x of the reference point (material = p_ref, damping as given, effects neutral).
  std::vector<double> reference_x() const;

  // Everything x stands for.
  TubeParams material(const std::vector<double>& x) const;
  model::RayleighDamping damping(const std::vector<double>& x) const;
  model::EffectSet effects(const std::vector<double>& x) const;
  double effect_value(const std::vector<double>& x, int index) const;  // SI value of param `index`

  // Reported impedance on a grid (linearised port model around the reference).
  std::vector<std::complex<double>> impedance(const std::vector<double>& x, const std::vector<double>& f_hz) const;
  // Exact port model at x (one FE modal solve).
  model::ModalPortModel exact_port(const std::vector<double>& x) const;

  // Moves the linearisation point to x's material/mass (5–6 modal solves).
  // Returns the largest material coordinate change since the last reference, in x units.
  double relinearise(const std::vector<double>& x);
  // Largest |x_i − x_i(linearisation point)| over the material coordinates.
  double distance_from_linearisation(const std::vector<double>& x) const;

 private:
  struct Linear;
  model::ModalPortModel port_at(const TubeParams& p, double mass_fraction) const;
  double mass_of(const std::vector<double>& x) const;  // end-mass fraction x stands for (fixed or fitted)

  model::ModalSolver* solver_;
  model::EffectSet fixed_;
  MaterialClass cls_;
  TubeParams p_ref_;
  model::RayleighDamping damping0_;
  double r1_;
  double w_ref_;
  int n_modes_;
  std::vector<GapParamInfo> params_;
  std::shared_ptr<Linear> lin_;
};

}  // namespace piezo::update
