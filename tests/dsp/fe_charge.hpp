#pragma once
// Seed §5.1 on OUR FE tube as the seed ran it (test support): the tube's port
// model of fe_chapter5.hpp (published APC850 tube, 24 short-circuit modes +
// residual mode) driven by the ANALYTIC voltage v(t) = 500·e^{−0.001 t} V from
// t = 0 (eq. 111, γv = 500 V, λv = −1e-3 1/s), its electrode CHARGE recorded at
// 10 MS/s for 5 ms (model/transient.hpp ChargeSimulator: exact for the
// piecewise-linear drive, at rest at t = 0, so the step at t = 0 is in it).
// §5.1.1: Rayleigh β = 0 (no damping), noise-free. §5.1.2: α = 0, β = 1e-7 s,
// white noise of std = level·std(clean charge over the 5 ms record) — the
// seed's σn/σs, the same definition the divider study uses per channel.
//
// The same charge as an exact pole–residue sum, built here from the port model
// independently of model/transient.cpp:
//   Q(s) = V(s)·C(s),  C(s) = C_e + Σ_k p_k²/(s² + c_k s + ω_k²),  C_e = C0 + C_res,
// so the residue at λv is γv·C(λv) and at a mode root λ_k (Im > 0)
// γv/(λ_k − λv)·p_k²/(λ_k − conj λ_k). It feeds the Cramér–Rao bound of the
// features of Z = V/(sQ) (one channel, the charge; V known).
#include <complex>
#include <cstdint>
#include <vector>

#include "dsp/prony_charge.hpp"
#include "fe_chapter5.hpp"
#include "impedance_study.hpp"

namespace piezo::fe5 {

struct ChargeData {
  const FeChapter5* fe = nullptr;  // the port model (outlives this)
  model::RayleighDamping damping;
  dsp::ExponentialDrive drive{500.0, -1e-3};
  double sample_rate_hz = 1e7;
  std::vector<double> q;  // clean charge from t = 0, 5 ms
  // Pole–residue form: real poles and one Im > 0 member per pair.
  std::vector<std::complex<double>> poles, residues;
  std::complex<double> z(double f_hz) const;  // the port model's harmonic Z (stepped-sine truth)
  double q_exact(double t) const;             // the pole–residue sum at t >= 0
};

ChargeData charge_data(const FeChapter5& fe, double beta);

// `level`·std(clean charge over the record): the seed's noise definition.
double charge_noise_std(const ChargeData& d, double level);

// One noisy copy of the first n samples (seeded white noise).
std::vector<double> noisy_charge(const ChargeData& d, double level, std::uint64_t seed, std::size_t n);

// The study's truth: Z and its |Z| extrema in 1–120 kHz (v1/v2 left empty).
study::StudyInput charge_study_input(const ChargeData& d);

// CRB (relative 1σ) of each true |Z| extremum of `in` from the first n charge
// samples at noise `level`: delta method on d ln|Z(jω)|/dω = 0 with
// Z = V/(s·Q) (V known), the Fisher matrix of the one-channel exponential model
// over the drive pole and the `pairs` mode pairs below f_max_hz with the largest
// charge residues, the other components known (the reduced class of
// fe_chapter5.hpp: a lower bound of the full one).
FeatureBounds charge_feature_crb(const ChargeData& d, const study::StudyInput& in, double level,
                                 std::size_t n, double f_max_hz = 130e3, std::size_t pairs = 3);

}  // namespace piezo::fe5
