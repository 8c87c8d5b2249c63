#pragma once
// Stepped-sine (lock-in) estimator (seed §4.1, §5.2): one shot per frequency; after
// the settling time each channel is fitted with a + b·cos ωt + c·sin ωt by least
// squares (the IEEE 1057 three-parameter sine fit at the known drive frequency),
// V = b − jc, and Z = R1·V2/(V1 − V2). The fit's covariance (residual variance)
// gives the per-point uncertainty.
#include <Eigen/Core>
#include <span>

#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct SineShot {
  DividerRecord record;
  double frequency_hz = 0.0;
};

struct SteppedSineOptions {
  double settle_s = 0.0;           // skipped after t = 0 (transient of the drive)
  double settle_fraction = 0.25;   // used when settle_s == 0: fraction of the record
  bool whole_periods = true;       // trim the fitted span to whole drive periods
  bool refuse_clipped = true;
  FeatureOptions features;
};

struct Phasor {
  std::complex<double> value;  // amplitude·e^{jφ} of x(t) = |V| cos(ωt + φ)
  double sigma = 0.0;          // sqrt(E|δV|²)
  double offset = 0.0;
};

// Least-squares phasor of x at frequency f (sampled at fs), t_k = k/fs.
Phasor lock_in(std::span<const double> x, double sample_rate_hz, double f_hz);

// Points sorted by frequency; shots at equal frequencies are kept as given.
ImpedanceResult impedance_stepped_sine(std::span<const SineShot> shots,
                                       const SteppedSineOptions& opt = {});

}  // namespace piezo::dsp
