#pragma once
// Independent analytic transducer model for the dsp tests: a Butterworth–Van Dyke
// equivalent circuit (C0 in parallel with motional R–L–C branches) driven through
// the divider resistor R1 by the seed's exp_decay v1(t) = A·e^{−a t}, t >= 0.
// The response is a finite sum of exponentials with closed-form coefficients, so
// the true poles, the true Z(jω) and v2 at every sample are known exactly.
#include <complex>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace piezo::bvd {

struct Branch {
  double L = 0, C = 0, R = 0;
};

struct Bvd {
  double c0 = 0;
  std::vector<Branch> branches;
  std::complex<double> admittance(std::complex<double> s) const;
  std::complex<double> impedance_at(double f_hz) const;
  double static_capacitance() const;  // C0 + Σ C_n: the low-frequency capacitance
};

// Lossless tuning: series resonances at fr (short-circuit modes, |Z| minima) and
// parallel resonances at fa (open-circuit modes, |Z| maxima), solved exactly for
// the motional C_n; then R_n from a damping ratio per branch.
Bvd make_bvd(const std::vector<double>& fr_hz, const std::vector<double>& fa_hz, double c0,
             const std::vector<double>& damping_ratio);
// Rayleigh damping of the branches: ξ_n = (α/ω_n + β ω_n)/2 (seed eq. 167).
Bvd make_bvd_rayleigh(const std::vector<double>& fr_hz, const std::vector<double>& fa_hz,
                      double c0, double alpha, double beta);
// The tube-like default: 50.3/51.1, 53.4/54.0, 79.4/95.1 kHz, C0 = 2.5 nF.
Bvd tube_bvd_q(double q = 200.0);
Bvd tube_bvd_rayleigh(double beta = 1e-7);

// A real signal Σ r_n e^{λ_n t} (conjugate pairs both present).
struct ExpSum {
  std::vector<std::complex<double>> lambda, residue;
  double at(double t) const;
  std::complex<double> laplace(std::complex<double> s) const;  // Σ r/(s − λ)
};

struct DividerResponse {
  ExpSum v1, v2, i;  // i = (v1 − v2)/R1
  std::vector<std::complex<double>> circuit_poles;  // poles of the loaded circuit
};

DividerResponse divider_response(const Bvd& bvd, double r1, double amplitude, double decay_per_s);

// Samples k = 0..n−1 at t = (k − pretrigger)/fs; zero before t = 0.
std::vector<double> sample(const ExpSum& x, double fs, std::size_t n, std::size_t pretrigger = 0);

// x + white Gaussian noise of std = fraction·std(x) (the seed's noise definition, §5.1.2).
std::vector<double> add_noise(const std::vector<double>& x, double fraction, std::uint64_t seed);
double std_dev(const std::vector<double>& x);

}  // namespace piezo::bvd
