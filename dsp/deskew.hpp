#pragma once
// Channel deskew: the DAQ samples channel 2 (v2) `skew_s` later than channel 1
// (v1), so the measured transfer is T_m(ω) = T(ω)·e^{−jωτ} and every
// estimator's Z = R1·T_m/(1 − T_m) carries a phase error that grows with f
// (and, through 1 − T_m, a magnitude error where T ≈ 1). The delay is
// estimated from a calibration shot and removed either from the record
// (deskew_channel: before any estimator, exact also for the drive's jump) or
// from Z(f) of any estimator:
//   T_m = Z_m/(Z_m + R1),  T = T_m·e^{+jωτ},  Z = R1·T/(1 − T).
// The accurate estimate (the fixture fit, fixture_calibration.hpp) separates
// the delay from the fixture's own R1·Cp lag; the two estimators here are the
// raw views it starts from.
#include <Eigen/Core>
#include <span>
#include <vector>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

// Delay of v2 relative to v1 (s, > 0: v2 late) from the cross-correlation of
// the first differences of the two records (a drive step becomes an impulse),
// refined below one sample by a parabola through the peak and its neighbours
// of the 8×-interpolated correlation (zero-padded FFT). Any lag of the
// circuit between v1 and v2 (R1·Cp of an open fixture: ~0.3 µs) is included:
// use a low-impedance shot (short, load) where that lag is small, or the fixture fit.
double xcorr_delay(std::span<const double> v1, std::span<const double> v2, double sample_rate_hz,
                   double max_delay_s = 2e-6);

// Delay from the phase slope of a transfer that should be real (a resistive
// load shot): least-squares slope of unwrapped arg T_m(ω) against −ω through
// the origin, weighted by |T_m|.
double phase_slope_delay(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& t_measured);

// Time-domain deskew of a channel recorded `delay_s` late (x[k] = v(t_k − delay)):
// returns y[m] = v(t_m), i.e. x at the fractional index m + delay·fs, by
// 4-point Lagrange interpolation that never mixes samples across the drive's
// jump at t = 0 (record index `jump_index`, the first sample of the excitation;
// in x the jump sits at jump_index + delay·fs). The sampled jump has no
// sub-sample position of its own, so a plain fractional delay (or a phase
// ramp on the spectrum) would smear it over the neighbouring samples; here it
// lands exactly on jump_index, as in channel 1. A sample that falls exactly
// on the jump (within 0.05 sample: an integer delay, or none) is left out of both sides. Samples
// beyond the record's ends are extrapolated from the nearest ones. Same length as x.
std::vector<double> deskew_channel(std::span<const double> x, double sample_rate_hz,
                                   std::size_t jump_index, double delay_s);

// Z → T = Z/(Z + R1) and back.
Eigen::VectorXcd divider_transfer(const Eigen::VectorXcd& z_ohm, double r1_ohm);
Eigen::VectorXcd divider_impedance(const Eigen::VectorXcd& t, double r1_ohm);

// Removes a channel-2 delay `skew_s` from an impedance estimated with nominal
// R1 `r1_ohm`: Z(f) and (first order) the per-point σ. Positive skew: v2 sampled late.
void deskew_impedance(ImpedanceResult& r, double r1_ohm, double skew_s);
Eigen::VectorXcd deskew_impedance(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z_ohm,
                                  double r1_ohm, double skew_s);

}  // namespace piezo::dsp
