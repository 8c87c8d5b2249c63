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

#include "dsp/impedance_types.hpp"
#include "dsp/prony_ss.hpp"

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
  std::size_t samples = 0;                        // samples per channel that entered the estimate
  std::vector<double> res_err_rel, anti_err_rel;  // per true feature; NaN = not found
  std::size_t ambiguous = 0;       // true features with > 1 found extremum within ±3 % (see match)
  double max_feature_err_rel = 0;  // worst over features (inf if one is missing)
  double max_db_err = 0, median_db_err = 0;  // |Z| away from the peaks, f_lo..f_hi
  double f_max_db_err = 0;                   // where the largest |Z| error sits
  std::size_t order = 0;                     // Prony only
  double elapsed_ms = 0;
  std::vector<double> f_hz;  // the estimate as computed (for plots)
  std::vector<std::complex<double>> z_ohm;
};

// One method over many noise seeds: per true feature the mean and std of the
// relative error over the runs that found it, and how many did; the median and
// 90th percentile of the max |Z| error and the median of the median error.
struct MethodStats {
  std::string method;
  std::size_t samples = 0, runs = 0;
  std::vector<double> res_mean, res_std, anti_mean, anti_std;
  std::vector<std::size_t> res_found, anti_found;
  double max_db_median = 0, max_db_p90 = 0, median_db_median = 0;
  double ambiguous_fraction = 0;  // of the (run, feature) pairs
};
MethodStats summarize(const std::vector<StudyRow>& runs);

// Within ±peak_exclusion_rel of a true feature (left out of the |Z| scores).
bool near_feature(const StudyInput& in, double f_hz);

// Prony-SS on the first `samples` samples of record 0; `prony` as given except
// that band_hz = 0 becomes the study band's top (f_hi_hz: decimation D = fs/(5·band)).
// Scores an estimate of any method (e.g. the charge path, dsp/prony_charge.hpp)
// against the truth of `in` exactly as the methods below are scored.
StudyRow study_result(const StudyInput& in, const dsp::ImpedanceResult& r, const std::string& method);

StudyRow study_prony(const StudyInput& in, std::size_t samples, dsp::PronyOptions prony = {});
StudyRow study_fft(const StudyInput& in, bool difference = true);
StudyRow study_xspec(const StudyInput& in, std::size_t segment, bool difference = true);
// Markdown tables.
std::string format_table(const std::vector<StudyRow>& rows);
std::string format_stats(const std::vector<MethodStats>& stats);

}  // namespace piezo::study
