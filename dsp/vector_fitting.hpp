#pragma once
// Vector fitting (Gustavsen & Semlyen, IEEE Trans. Power Delivery 14(3), 1999):
// a rational model with STABLE poles fitted to samples of a frequency response,
//     H(s) ≈ Σ_n r_n/(s − a_n) + d + s·e,   Re a_n < 0,
// by iterated pole relocation (the zeros of the weighting function σ(s) become
// the new poles; unstable ones are reflected into the left half-plane), then
// a linear least-squares fit of the residues. Poles come in complex-conjugate
// pairs (or are real) and d, e, the residue pairs are real/conjugate, so the
// model is the transform of a real, causal, stable impulse response: it obeys
// the Kramers–Kronig relations by construction (kramers_kronig.hpp).
#include <Eigen/Core>
#include <complex>

namespace piezo::dsp {

struct VectorFitOptions {
  int pole_pairs = 8;  // starting complex pairs, spread over the band
  int iterations = 12;
  bool proper_term = true;  // d
  bool slope_term = true;   // s·e
  // Poles kept within |a| ≤ max_pole_ratio·2π·f_max (0: anywhere). A pole far
  // beyond the band acts in it like a polynomial in s, which can mimic any
  // smooth phase error — a time shift included — and so blinds a causality test.
  double max_pole_ratio = 0.0;
};

struct VectorFit {
  Eigen::VectorXcd poles;     // all poles (conjugates included), Re < 0
  Eigen::VectorXcd residues;  // one per pole
  double d = 0.0, e = 0.0;
  std::complex<double> eval(std::complex<double> s) const;
};

// Samples H(j2πf_k), weights w_k (1/σ; empty: 1/|H|). Throws std::invalid_argument
// for fewer samples than unknowns or non-finite data.
VectorFit vector_fit(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& h,
                     const Eigen::VectorXd& weights, const VectorFitOptions& opt = {});

}  // namespace piezo::dsp
