#pragma once
// The tube seen from its electrodes, in modal form (what impedance sweeps and
// the time-domain bench need). With the short-circuit modes φ_k (mass-
// normalised, K_sc φ_k = ω_k² M φ_k) and g the electrode load vector after
// condensing the internal potentials:
//   M Ü + C U̇ + K_sc U = −g V,   Q = C0 V − gᵀU                 (eqs 87-92)
// so each mode is a 2nd-order system driven by the electrode voltage with
// participation p_k = gᵀφ_k, and
//   Q/V = C0 + C_res + Σ_k p_k² / (ω_k² − ω² + jω c_k),  c_k = α + β κ_k,
// κ_k = φ_kᵀ K_UU φ_k (Rayleigh C = αM + βK_UU projected on the modes).
// The modes above the computed ones are lumped into ONE residual pseudo-mode
// (ω_r, p_r) matching their first two moments exactly:
//   Σ_{k>N} p_k²/ω_k² = C_static − C0 − Σ_{k≤N} p_k²/ω_k²              (static)
//   Σ_{k>N} p_k²/ω_k⁴ = U_sᵀ M U_s − Σ_{k≤N} p_k²/ω_k⁴   (U_s: static shape, V = 1)
// so the model is exact at ω → 0 and the truncation error is O((ω/ω_N+1)⁴)
// instead of O((ω/ω_N+1)²) for a static correction only; being a mode, it is
// causal and usable in the time domain (model/transient.hpp).
#include <complex>
#include <limits>
#include <span>
#include <vector>

#include "model/material.hpp"

namespace piezo::model {

struct RayleighDamping {
  double alpha = 0.0;  // 1/s, mass-proportional
  double beta = 0.0;   // s, stiffness-proportional (seed ch. 5: β = 1e-7 s)
  void validate() const;
};

struct PortMode {
  double omega = 0;          // rad/s (short circuit)
  double participation = 0;  // p_k = gᵀφ_k
  double kappa = 0;          // φ_kᵀ K_UU φ_k (for βK_UU damping and Qm)
  bool symmetric = false;    // about the mid-plane
  bool residual = false;     // the pseudo-mode standing for all truncated modes
  // Damping added to c_k by an acoustic load on the outer surface (1/s;
  // ModalOptions::outer_surface_impedance, model/outer_surface_damping.hpp).
  // A simulator input only (acquisition/divider_state_space.cpp adds it):
  // charge_per_volt and the diagnosis ignore it. 0 unless asked for, and 0 on
  // the residual pseudo-mode.
  double radiation_damping = 0;
};

struct ModalPortModel {
  double c_clamped = 0;   // C0: U = 0, internal potentials free (F)
  double c_static = 0;    // free tube at ω → 0 (F)
  double c_residual = 0;  // static share of truncated modes NOT carried by a residual mode (F)
  std::vector<PortMode> modes;  // elastic short-circuit modes, ascending (+ residual mode last)
  bool converged = true;        // the modal solve behind it converged
  bool reduced_basis = false;   // from a reduced basis (model/reduced_port.hpp), not a modal solve
  double end_mass_fraction = 0;  // end-face mass loading of the modes (model/end_mass.hpp)
  // εT33/εS33 of the material: a loss of the FREE permittivity (the ceramic's
  // tanδ as datasheets quote it, εT33 → εT33·(1 − j·tanδ)) reaches the clamped
  // capacitance magnified by this ratio (εS33 = εT33 − 2d31e31 − d33e33).
  double eps_t_over_s = 1.0;

  // Q/V at angular frequency ω (≥ 0) with Rayleigh damping and, optionally,
  // Qm / tanδ on cE / εS (complex constants, first-order modal approximation:
  // ω_k² → κ_k(1 + j/Qm) + (ω_k² − κ_k)/(1 − j tanδ), C0 → C0(1 − j tanδ);
  // derivation in port_model.cpp; the direct solve in model/harmonic.hpp is exact).
  std::complex<double> charge_per_volt(double omega, const RayleighDamping& d,
                                       const MaterialLosses& l = {}) const;
};

// The residual pseudo-mode (above) appended to p, whose elastic modes,
// c_clamped and c_static are set: from C_static − C0 − Σ p_k²/ω_k² and
// shape_mass = U_sᵀ M U_s − Σ p_k²/ω_k⁴; c_residual keeps the static share
// when the two moments do not make a mode above the computed ones.
void add_residual_mode(ModalPortModel& p, double shape_mass);
// A port model of the upper half (TubeExtent::upper_half) as the whole tube's:
// two mirrored halves in parallel (model/modal.cpp, ModalSolver::port_model).
void half_to_whole(ModalPortModel& p);

}  // namespace piezo::model
