#pragma once
// Direct FFT ratio (seed §4.1, §5.1.1): Z(f_k) = R1·V2(f_k)/(V1(f_k) − V2(f_k)) from
// one record, on the FFT bins f_k = k·fs/nfft. Suffers from the periodic
// assumption (leakage) and a resolution of fs/nfft; kept as the reference the
// Laplace method is compared with. Per-point uncertainty by first-order
// propagation of white noise of the estimated std on v1 and v2.
#include <Eigen/Core>

#include "dsp/divider.hpp"
#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"
#include "dsp/windows.hpp"

namespace piezo::dsp {

struct FftRatioOptions {
  DividerPrep prep;        // prep.max_samples: record length from t = 0 (0: all)
  Window window;           // default rectangular: a transient starts at t = 0
  std::size_t nfft = 0;    // 0: the record length (no zero padding)
  // First difference of both channels before the FFT. Z = V2/(V1 − V2) is
  // unchanged (the same filter on both), but a drive step becomes an impulse, so
  // the periodic extension of a step/exp_decay record has no jump: without it
  // V1(f_k) of a step held to the record's end is ~0 off DC and Z is garbage.
  bool difference = true;
  // The record starts with the drive's jump at t = 0 (sample 0): sample 0 counts
  // half (trapezoid rule at the jump), so Σ x[k]e^{−jωkΔt} follows the one-sided
  // continuous transform. A plain DFT puts the jump half a sample early, a
  // phase error ωΔt/2 of V1 against a continuous V2 (2° at 120 kHz, 10 MS/s).
  // Off by default: the plain DFT ratio is this estimator's reference form.
  bool one_sided = false;
  // With `difference`, the record's last sample enters every bin whole (the
  // difference telescopes: D = (1 − e^{−jθ})·X + x_{n−1} on the DFT bins), so
  // its noise is common to all bins and, below fs/(2π·√n), most of their
  // noise. end_fit_samples = M > 0: that sample is replaced by the value at
  // the end of a quadratic least-squares fit to the last M samples, ~3/√M of
  // the noise (M = 1000: 0.1 ms at 10 MS/s). Needs a record that is smooth
  // over its last M samples (a decaying transient); 0: as recorded.
  std::size_t end_fit_samples = 0;
  double fmin_hz = 0.0, fmax_hz = 0.0;  // bins kept; fmax 0: Nyquist
  FeatureOptions features;
};

ImpedanceResult impedance_fft(const DividerRecord& rec, const FftRatioOptions& opt = {});

}  // namespace piezo::dsp
