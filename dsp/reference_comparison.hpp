#pragma once
// An impedance estimate scored against a known true impedance — the figures of
// merit of the seed's §5.1 (Figs 25–29: the estimate's |Z| against the FE's
// stepped-harmonic |Z|), used by the chapter-5 studies (tests/dsp) and by
// `piezobench model charge` (jobs/charge_study_job.hpp).
//
// |Z| error: |20·log10(|Z_est|/|Z_true|)| on the estimate's own grid inside
// [f_lo, f_hi], away from the peaks (outside ±peak_exclusion_rel of every true
// |Z| extremum: with light damping the true |Z| is near 0 or ∞ there, so any
// frequency error, however small, makes the dB error unbounded). Features: per
// true extremum the nearest found one within ±3 %; `ambiguous` counts true
// features with more than one candidate there (a noisy curve), whose error is
// then optimistic (the truth picked it).
#include <complex>
#include <cstddef>
#include <functional>
#include <vector>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct ImpedanceTruth {
  std::function<std::complex<double>(double)> z;  // the true Z(f)
  std::vector<double> resonances_hz, antiresonances_hz;  // its |Z| minima and maxima
  double f_lo_hz = 1e3, f_hi_hz = 120e3;
  double peak_exclusion_rel = 0.015;
};

// The true |Z| extrema of `z` in [f_lo_hz, f_hi_hz] (dsp/features.hpp on a grid of step_hz, refined).
ImpedanceTruth impedance_truth(std::function<std::complex<double>(double)> z, double f_lo_hz = 1e3,
                               double f_hi_hz = 120e3, double step_hz = 10.0);

struct TruthComparison {
  std::vector<double> res_err_rel, anti_err_rel;  // per true feature; NaN: not found
  std::size_t ambiguous = 0;
  double max_feature_err_rel = 0;  // worst over the features (inf when one is missing)
  double max_db_err = 0, median_db_err = 0;
  double f_max_db_err = 0;  // where the largest |Z| error sits
  std::size_t scored = 0;   // grid points that entered the |Z| error
};

// Within ±peak_exclusion_rel of a true feature (left out of the |Z| error).
bool near_true_feature(const ImpedanceTruth& truth, double f_hz);

TruthComparison compare_to_truth(const ImpedanceTruth& truth, const ImpedanceResult& estimate);

}  // namespace piezo::dsp
