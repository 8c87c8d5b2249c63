#pragma once
// Per-mode figures of an updated FE model (issue 34 item 3): the figures
// "from the updated FE model follow the definitions from its short- and
// open-circuit modes". The port model (model/port_model.hpp, seed eqs 87-92)
//   Q/V = C0 + C_res + Σ_k p_k² / (ω_k² − ω² + jω c_k)
// IS a multi-branch Butterworth–Van Dyke network: each mode's admittance
// jω·p_k²/(ω_k² − ω² + jωc_k) is the series branch
//   L_k = 1/p_k²,  C_k = p_k²/ω_k²,  R_k = c_k/p_k²   (c_k = α + βκ_k)
// (complex constants: R_k = ηκ_k/(ω_k p_k²), the hysteretic loss at its
// resonance). So fs_k is the short-circuit mode's frequency exactly, and fp_k
// — the zero of the lossless network's susceptance above fs_k — the open-
// circuit mode's (up to the inactive modes lumped into C0, below; the test
// checks it against the open-circuit modal solve). The electrically active modes
// (symmetric, coupling p²/(ω²C0) above ModalOptions::active_coupling) become
// branches (a weak one between a strong one's fs and fp has no fp of its
// own: dsp/equivalent_circuit's "guest"); the others' static share p²/ω² and
// C_res go into C0, the residual
// pseudo-mode stays a branch (it bounds fp of the highest mode) but is never
// reported. Every IEEE 176 / EN 50324-2 figure of dsp::circuit_mode_figures
// follows.
//
// σ: the constants' covariance (relative coordinates of the output-error fit:
// ln YE11, nu12/nu12₀ − 1, ln d31, ln εT33, ln of the loss) pushed through the
// figures along its principal axes: g(θ̂ ± √λ_j v_j), σ_g² = Σ_j ((g₊ − g₋)/2)²
// — 2·5 more port models. A lack of fit of the capture is in that covariance
// already (Birge-widened by the fit).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "dsp/equivalent_circuit.hpp"
#include "model/effects.hpp"
#include "model/modal.hpp"
#include "update/output_error.hpp"
#include "update/parametrization.hpp"

namespace piezo::update {

struct ModelFigures {
  dsp::EquivalentCircuit circuit;            // active modes + the residual pseudo-mode as branches
  std::vector<dsp::CircuitModeFigures> modes;  // the active modes with fs in the band, ascending, with σ
  dsp::Figure c0_f;                          // C0 + C_res + the inactive modes' static share
  dsp::Figure free_capacitance_f;            // C^T: the port model's static capacitance
  dsp::Figure tan_delta;                     // of C0 (0: the five-parameter model has no dielectric loss)
  int port_models = 0;                       // FE port models built (1 + 2 per principal axis)
  std::vector<std::string> notes;
};

// The branches of one port model, without σ (what the σ propagation evaluates).
dsp::EquivalentCircuit port_circuit(const model::ModalPortModel& port, const OeLoss& loss,
                                    double active_coupling);

// `covariance_rel`: 5 × 5 in the fit's relative coordinates (empty: no σ).
// Modes with fs outside [band_lo_hz, band_hi_hz] are not reported. Throws
// std::runtime_error when the FE port model cannot be built.
ModelFigures model_figures(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& params,
                           const OeLoss& loss, const Eigen::MatrixXd& covariance_rel, double band_lo_hz,
                           double band_hi_hz, const model::ModalOptions& modal = {},
                           const model::EffectSet& effects = {});

// The covariance of an output-error fit in its relative coordinates with the
// type-B part included: the statistical covariance (OeResult::covariance_rel)
// rescaled per coordinate to the total sigma of each constant (R1's tolerance,
// the cable capacitance, the channel gain: OeParameter::sigma), its
// correlations kept.
Eigen::MatrixXd total_covariance_rel(const OeResult& r);

}  // namespace piezo::update
