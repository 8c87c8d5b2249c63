#pragma once
// Kramers–Kronig (causality and linearity) test of an estimated impedance.
//
// The real and imaginary parts of a causal, linear, stable response are
// Hilbert transforms of each other. Instead of the KK integrals, which need
// data from 0 to ∞, the test fits the data with a model that satisfies them
// by construction — a rational function with only stable poles (vector
// fitting, vector_fitting.hpp; the "measurement model" approach of Agarwal,
// Orazem & García-Rubio, J. Electrochem. Soc. 139, 1992, and the linear KK
// test of Schönleber et al., Electrochim. Acta 131, 2014, whose RC elements
// cannot represent resonances) — and looks at what it cannot explain:
//   residual(f) = |X(f) − X_KK(f)| / |X(f)|.
// A driving-point impedance of a passive network is positive-real: BOTH Z and
// Y = 1/Z are causal, and Re Z(jω) ≥ 0. Both forms are fitted (Z as s·Z,
// finite at DC), and passivity is checked point by point.
//
// What no finite-band test can see: a pure time shift. e^{−jωΔ}·Z = Z − jωΔ·Z
// + …, and every term of that series is causal; on a band the series is just
// another smooth function (Runge: stable rational functions approximate it).
// A channel-2 DELAY (a wrong deskew sign on a late channel) makes a capacitive
// Z look active, Re Z ≈ −|Z|·sin(ωΔ) < 0: the passivity check fails at once.
// A channel-2 ADVANCE adds Re Z ≈ |Z|·sin(ωΔ) > 0 and looks like a series
// resistance Δ/C to first order: causal and passive in the band, undetectable.
//
// Pass: rms(causality residual) ≤ threshold in both forms and, at every f,
// −Re Z/|Z| ≤ threshold (+ noise_factor·σ/|Z| there), threshold =
// max(threshold_rel, noise_factor × rms(σ/|Z|)) when σ is known.
//
// Cost. Vector fitting is O(N·P²) in memory-bound dense algebra for N points
// and P poles, and P grows with the |Z| extrema found — on a noisy 10 000-bin
// FFT grid thousands of them. So the rational models are FITTED on a thinned
// grid of at most max_fit_points points, chosen by arc length of ln Z (points
// crowd where Z turns — resonances, anti-resonances — and thin out where it is
// smooth, always including both band edges), with at most max_pole_pairs
// pairs; residuals and passivity are then EVALUATED on the full grid, O(N·P).
// Each σ-weighted fitted point stands for the points it replaces (its weight
// is scaled by √(points represented)), so the fit weighs the band as the full
// grid would. Time and memory: O(N + M·P²) for M ≤ max_fit_points.
#include <Eigen/Core>
#include <string>

namespace piezo::dsp {

struct KramersKronigOptions {
  int pole_pairs = 0;  // 0: automatic, 2 + the |Z| extrema found in the band, at least 4
  int iterations = 15;
  double threshold_rel = 0.005;  // rms relative residual for a pass without σ
  double noise_factor = 3.0;    // with σ: also pass while the residual is within this × the noise
  double max_pole_ratio = 0.0;  // 0: poles anywhere (see VectorFitOptions)
  int max_fit_points = 600;     // the thinned grid the rational models are fitted on
  int max_pole_pairs = 40;      // cap of the automatic (and of a given) pole count
};

struct KramersKronigResult {
  bool pass = false;
  double threshold = 0.0;
  double rms_residual = 0.0, max_residual = 0.0, max_residual_f_hz = 0.0;
  double rms_residual_z = 0.0, rms_residual_y = 0.0;
  Eigen::VectorXd f_hz;
  Eigen::VectorXd residual;  // per f: the largest of the Z-, Y-form and passivity residuals
  Eigen::VectorXd residual_z, residual_y;
  Eigen::VectorXd passivity;  // per f: max(0, −Re Z)/|Z|
  double max_passivity = 0.0, max_passivity_f_hz = 0.0;
  bool causal = false, passive = false;
  int pole_pairs = 0;
  int fit_points = 0;  // points of the thinned grid the models were fitted on
  std::string note;  // which form failed, or why the test could not run
};

// z_sigma (same length or empty): sqrt(E|δZ|²) per point. Throws
// std::invalid_argument for mismatched lengths, < 16 points, non-finite Z.
KramersKronigResult kramers_kronig_check(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z_ohm,
                                         const Eigen::VectorXd& z_sigma_ohm,
                                         const KramersKronigOptions& opt = {});

}  // namespace piezo::dsp
