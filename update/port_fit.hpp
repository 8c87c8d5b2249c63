#pragma once
// Measured features by a time-domain output-error fit of the tube's modal port
// model to a divider capture — the refinement step after Prony-SS.
//
// The tube seen from its electrodes is (model/port_model.hpp, seed eqs 87-92)
//     Q/V = C_e + Σ_k q_k / (ω_k² − ω² + jω c_k),   q_k = p_k²,
// a multi-branch Butterworth–Van Dyke network: ω_k are the short-circuit modal
// frequencies (the resonances), the real roots of C_e + Σ q_k/(ω_k² − ω²) the
// open-circuit ones (the anti-resonances), and C_e + Σ q_k/(ω_k² − ω²) at a low
// ω the capacitance. With K modes from Prony's features (plus, optionally, one
// pseudo-mode above them for the modes out of band), the divider response to
// the recorded v1 is simulated exactly (model::DividerSimulator, first-order
// hold) and θ = ln(C_e, ω_k, q_k, c_k) is fitted to the recorded v2 by
// Levenberg–Marquardt: with white noise on v2 this is the maximum-likelihood
// estimate, so it attains the Cramér–Rao bound asymptotically, while Prony's
// features (the zeros/poles of a low-order rational fit) carry a truncation
// bias where the model order is set by the noise — on the seed's tube the third
// resonance (the zero of Z between 54 and 95 kHz) sits +0.2…0.3 % high at 3 %
// noise, which alone moves nu12 by +1 % (docs/update-methods.md).
// Uncertainties: Gauss–Newton covariance σ̂²(JᵀJ)⁻¹ propagated to the features.
#include <span>
#include <string>
#include <vector>

#include "model/port_model.hpp"
#include "update/features.hpp"

namespace piezo::update {

struct PortFitStart {
  std::vector<double> resonances_hz;      // ascending, one per fitted mode
  std::vector<double> antiresonances_hz;  // same count: the open-circuit partner of each
  std::vector<double> damping_ratios;     // of the resonances (empty: 0.01 each)
  double capacitance_f = 0;               // low-frequency capacitance
};

struct PortFitOptions {
  int max_iterations = 60;
  double step_tolerance = 1e-9;  // converged when max |Δθ| < this (relative parameter change) …
  double feature_tolerance = 1e-7;  // … or no feature moved by more than this (relative)
  // Pseudo-modes above the band for the modes out of it, at these multiples of
  // the highest anti-resonance (held; their q and c are fitted).
  bool high_mode = true;
  std::vector<double> high_mode_factors = {2.5};
  double low_f_hz = 400.0;  // frequency of the reported capacitance / |Z|
  // The output error is low-pass filtered (causal windowed sinc, zero before
  // t = 0 where model and tube are both at rest) and decimated before it is
  // minimised, so the ringing of the modes far above the band (the step at
  // t = 0 excites them all) is not fitted by the few in-band branches.
  // 0: 1.5 × the highest starting anti-resonance.
  double band_hz = 0.0;
  // A measured fixture (issue 10's calibration) put into the divider the
  // port is simulated in (model::DividerCircuit): capacitance from node 2 to
  // ground and lead resistance between node 2 and the tube. r1_ohm of
  // fit_port_model is then the TRUE R1 (nominal × (1 + measured R1 error)).
  double fixture_capacitance_f = 0.0;
  double lead_resistance_ohm = 0.0;
};

struct PortFitResult {
  bool converged = false;
  std::string message;
  model::ModalPortModel port;  // fitted; mode.kappa holds c_k (use RayleighDamping{0, 1})
  MeasuredFeatures features;   // with 1-σ uncertainties from the fit
  double residual_rms_v = 0;   // of v2
  int iterations = 0;
};

// v1, v2: samples from t = 0 (excitation start, tube at rest), volts; r1_ohm: the
// divider's series resistor. Throws std::invalid_argument for bad input; a fit
// that does not converge is a status (converged = false, message).
PortFitResult fit_port_model(std::span<const double> v1, std::span<const double> v2,
                             double sample_rate_hz, double r1_ohm, const PortFitStart& start,
                             const PortFitOptions& options = {});

// Anti-resonances of a port model, one above each ω_k, in Hz: the real roots of
// C_e + Σ q_k/(ω_k² − ω²) (undamped), or with `damped` the natural frequencies
// |s*| of the complex zeros of Q/V(s) next to them, with the modal damping
// c_k = mode.kappa (the convention of PortFitResult::port).
std::vector<double> port_antiresonances_hz(const model::ModalPortModel& port, bool damped = false);
// Re Q/V of the undamped port model at f (F).
double port_capacitance(const model::ModalPortModel& port, double f_hz);

}  // namespace piezo::update
