#pragma once
// The chapter-5 comparison (seed §5.1.2) as a reusable helper: given noisy v1/v2
// records and the true Z(f), run Prony-SS on the first N samples of record 0,
// the direct FFT ratio on record 0 and the averaged cross spectra on all records,
// and score each against the truth. Re-pointable at FE data: it only needs the
// arrays, the sample rate, R1 and a callable true impedance.
#include <complex>
#include <functional>
#include <string>
#include <vector>

namespace piezo::study {

struct StudyInput {
  std::vector<std::vector<double>> v1, v2;  // records; record 0 feeds Prony and the FFT
  double sample_rate_hz = 0, r1_ohm = 0;
  std::size_t pretrigger = 0;
  std::function<std::complex<double>(double)> z_true;
  std::vector<double> true_resonances_hz, true_antiresonances_hz;
  double f_lo_hz = 1e3, f_hi_hz = 120e3;
  double peak_exclusion_rel = 0.015;  // |Z| error ignored within ±1.5 % of a true feature
  double prony_grid_hz = 200.0;
};

struct StudyRow {
  std::string method;
  std::size_t samples = 0;                      // samples per channel that entered the estimate
  std::vector<double> res_err_rel, anti_err_rel;  // per true feature; NaN = not found
  double max_feature_err_rel = 0;               // worst over features (inf if one is missing)
  double max_db_err = 0, median_db_err = 0;     // |Z| away from the peaks, f_lo..f_hi
  double f_max_db_err = 0;                      // where the largest |Z| error sits
  std::size_t order = 0;                        // Prony only
  double elapsed_ms = 0;
};

StudyRow study_prony(const StudyInput& in, std::size_t samples);
StudyRow study_fft(const StudyInput& in, bool difference = true);
StudyRow study_xspec(const StudyInput& in, std::size_t segment, bool difference = true);
std::string format_table(const std::vector<StudyRow>& rows);

}  // namespace piezo::study
