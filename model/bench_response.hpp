#pragma once
// What the divider bench REPORTS as the transducer's impedance when the
// catalogue's effects (model/effects.hpp) are present: the frequency-domain
// twin of the simulated bench (acquisition/divider_state_space.hpp), used by
// the gap diagnosis to fit effects as model extensions.
//
//   tube:      Y_t = jω·Q/V, Q/V from the port model with Rayleigh damping,
//              c_k += 2 ξ_m ω_k (mechanical_damping) and Ce = C0 + C_res made
//              lossy (dielectric_loss, see lossy_capacitance)
//   terminals: Z_a = 1/Y_t + R_s (series_resistance)
//   v2 node:   Y_n = 1/Z_a + jω C_p + 1/R_daq (parallel_capacitance, daq_input_resistance)
//   divider:   H = v2/v1 = Z_n / (Z_n + R1·(1 + r1_tolerance))
//   DAQ:       H' = H·(1 + channel_gain)·e^(−jωτ) (channel_skew τ: v2 sampled late)
//   estimate:  Z_reported = R1·H' / (1 − H')   (eq. 139 with the NOMINAL R1)
// The bench itself realises the lossy capacitance by a Debye network fitted
// over 100 Hz – 1 MHz, so the two agree to that network's accuracy.
#include <complex>
#include <span>
#include <vector>

#include "model/effects.hpp"
#include "model/port_model.hpp"

namespace piezo::model {

// Dielectric loss with a frequency-independent loss angle δ = atan(tanδ) must,
// to be causal (Kramers–Kronig), come with a slowly falling real part: the
// constant-phase capacitance
//   C(ω) = C·(ω/ω_ref)^(−2δ/π)·e^(−jδ),   f_ref = kDielectricLossRefHz,
// equal to C·(1 − j tanδ)·cos δ at the reference frequency (where εT33 is
// quoted) and rising by (2δ/π)·ln(10) ≈ 1.5·tanδ per decade below it.
constexpr double kDielectricLossRefHz = 1e3;
std::complex<double> lossy_capacitance(double c, double tan_delta, double omega);

// The non-motional part of the tube's Q/V at ω: C0 + C_res with the
// dielectric loss of `fx` applied to εT33 as the catalogue defines it
// (εT33 → εT33·φ(ω), φ = 1 − j·tanδ or the constant-phase law): the clamped
// capacitance is linear in εS33 = εT33 − 2d31e31 − d33e33, so
//   C0(ω) = C0·(1 + (εT33/εS33)·(φ(ω) − 1)),
// its loss tangent magnified by εT33/εS33 (ModalPortModel::eps_t_over_s);
// C_res (the truncated modes) is mechanical and lossless.
std::complex<double> port_capacitance(const ModalPortModel& port, const EffectSet& fx, double omega);

// The tube alone: Y_t(ω) with the damping and loss effects of `fx` (circuit
// and DAQ effects ignored). `elastic_loss` η = 1/Qm: the complex elastic
// constants cE·(1 + jη) (MaterialLosses::qm), hysteretic, first-order modal:
// ω_k² → ω_k² + jηκ_k (κ_k = φ_kᵀK_UUφ_k, so mode k's Qm is Qm·ω_k²/κ_k) — the
// alternative to Rayleigh damping of the output-error fit (OeDamping). The
// dielectric loss inside the wall (ModalPortModel::charge_per_volt, (ω_k² −
// κ_k)·tanδ per mode) is left out here, as the simulated bench
// (acquisition/divider_state_space.cpp) leaves it out: on the default tube it
// is (1 − κ_k/ω_k²)·tanδ = 4e-6 to 1.2e-4 of the strongly coupled modes' stiffness at tanδ 0.01
// (1.1e-3 on the weakly coupled ones with 11 % electrical stiffness).
std::complex<double> tube_admittance(const ModalPortModel& port, const RayleighDamping& d,
                                     const EffectSet& fx, double omega, double elastic_loss = 0.0);
// The same at every ω of `omega` (each > 0) into y (y.size() ≥ omega.size()):
// the same operations in the same order for each ω, bit-identical, but with
// the modes' loop outside so that the frequencies' loop vectorises (the
// output-error fit's inner loop, issue 43).
void tube_admittances(const ModalPortModel& port, const RayleighDamping& d, const EffectSet& fx,
                      std::span<const double> omega, double elastic_loss, std::span<std::complex<double>> y);

// H'(ω) = v2/v1 as the DAQ records it (the divider, then channel 2's gain and
// skew), from the tube's admittance and the circuit/DAQ effects: what the
// output-error fit (update/output_error.hpp) applies to the recorded v1.
std::complex<double> recorded_transfer(std::complex<double> y_tube, const EffectSet& fx,
                                       double r1_nominal_ohm, double omega);
// The same for every ω of `omega`, in place (y: the tube's admittances in,
// H' out; y.size() == omega.size()): the effects present found once, not per
// frequency; bit-identical to recorded_transfer at each ω.
void recorded_transfers(std::span<std::complex<double>> y, const EffectSet& fx, double r1_nominal_ohm,
                        std::span<const double> omega);

// Z_reported(ω) from the tube's admittance (any source) and the circuit/DAQ effects.
std::complex<double> reported_impedance(std::complex<double> y_tube, const EffectSet& fx,
                                        double r1_nominal_ohm, double omega);

// Both steps on a frequency grid (Hz).
std::vector<std::complex<double>> bench_impedance(const ModalPortModel& port,
                                                  const RayleighDamping& d, const EffectSet& fx,
                                                  double r1_nominal_ohm,
                                                  std::span<const double> f_hz,
                                                  double elastic_loss = 0.0);

}  // namespace piezo::model
