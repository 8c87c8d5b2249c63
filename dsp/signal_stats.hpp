#pragma once
// Per-channel summary statistics of a sampled signal and clipping detection,
// used by `capture info`, the acquisition runner and the estimators; the
// chance of a χ² (the significance tests of dsp/ and update/).
#include <cstddef>
#include <optional>
#include <span>

namespace piezo::dsp {

struct SignalStats {
  double min = 0.0;
  double max = 0.0;
  double rms = 0.0;
  double mean = 0.0;
  bool clipped = false;
  std::size_t samples_at_limit = 0;  // samples sitting at the detected limit
};

struct ClipDetection {
  // Known DAQ full-scale (volts, symmetric ±range). When set, a sample with
  // |x| >= range·(1 - rel_margin) counts as at the limit. The margin covers
  // converters whose largest code sits a few LSB below the nominal range
  // (two's-complement codes are asymmetric): 1/256 of full scale.
  std::optional<double> range_v;
  double rel_margin = 1.0 / 256.0;
  // Without a known range: the signal is clipped when it holds a run of at
  // least `min_flat_run` consecutive samples equal to its own extreme value of
  // largest magnitude (a converter pinned at full scale; the range is symmetric). ADC quantization of a smooth peak
  // gives runs of a few samples at most, see tests/dsp/test_signal_stats.cpp.
  std::size_t min_flat_run = 8;
};

SignalStats compute_stats(std::span<const double> x, const ClipDetection& clip = {});

// ln P(X ≥ x) for X ~ Gamma(w, 1): the chance that w bins of z = |e|²/var
// (each Exp(1) under noise) sum to x or more; with w = (ν + 1)/2 and x = χ²/2
// the chance of a χ² on ν degrees of freedom (exact for even ν).
double log_gamma_tail(int w, double x);

}  // namespace piezo::dsp
