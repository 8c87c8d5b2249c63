#pragma once
// A real bench's slow disturbances as nuisance of the output-error fit
// (issue 33 item 1). What the samples carry besides the divider's response
// and white noise:
//   baseline   per channel an offset, a slope and a low-order wander, and
//              mains hum at 50 or 60 Hz with its 2nd and 3rd harmonics. The
//              residual L ∗ (T ∗ v1 − v2) sees b(t) = T ∗ b1 − b2 ≈ b1 − b2 of
//              the channels' baselines b1, b2 (T is 1 at the mains' frequency
//              to 1e-3): the difference, never each channel's alone. It is
//              a linear nuisance: its filtered columns L ∗ {Legendre P0..P3
//              over the record, cos/sin(2π·h·f_mains·t)} are projected out of
//              the residual (variable projection: the constants' sigmas then
//              hold what the baseline takes of their information). Hum
//              columns enter only when the record spans half a cycle of
//              them — below that the polynomial holds them (and the mains
//              frequency cannot be told: reported as such).
//   1/f noise  coloured noise whose power spectrum rises as 1/f below the
//              white floor's: the residual is whitened by the filter
//              w(f) = 1/√(1 + b·f₁/f) (b the 1/f-to-white power ratio at the
//              record's first frequency bin f₁), so the white σ keeps its
//              meaning and χ² counts 1/f noise as noise, not as lack of fit.
// Both are decided on the data, at the first optimum (decide_disturbances):
// the baseline when projecting its columns lowers χ² beyond chance
// (p < 1e-3, Bonferroni over the mains frequencies tried), the 1/f term when
// the Whittle likelihood of the residual's periodogram prefers it by
// Δ(2 ln L) > 10.8 (p < 1e-3 for one parameter) with b estimated robustly
// (octave medians: a misfit near a few modes does not raise it). A capture
// without either keeps the white model, sample for sample as before.
// Internal to update/output_error/.
#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "update/output_error.hpp"
#include "update/output_error/common.hpp"
#include "update/output_error/forward_model.hpp"
#include "update/output_error/shot_average.hpp"

namespace piezo::update::oe {

// The 1/f whitening filter on the decimated residual (M samples): zero-padded
// to N ≥ 2M, multiplied by w(f) in frequency, the first M samples kept.
class PinkFilter {
 public:
  PinkFilter(std::size_t m, double b);
  Eigen::VectorXd operator()(const Eigen::VectorXd& r) const;  // thread-safe
  double b() const { return b_; }

 private:
  std::size_t m_, n_;
  double b_;
  std::vector<double> w_;  // n_/2 + 1 bins
};

// What decide_disturbances found.
struct DisturbanceModel {
  bool baseline = false;           // polynomial (and hum) columns projected out
  int poly_degree = 3;             // Legendre P0..P_degree
  double mains_hz = 0;             // the hum's frequency used (0: none in the columns)
  bool mains_known = false;        // given by the capture (/setup mains_hz)
  bool mains_distinguishable = false;  // 50 and 60 Hz told apart by the data
  int harmonics = 0;               // hum harmonics in the columns (0: record shorter than half a cycle)
  double baseline_delta_chi2 = 0;  // χ² the baseline's columns take beyond the offset's
  int baseline_dof = 0;            // their count beyond the offset
  double baseline_log10_p = 0;     // chance of that Δχ² under white noise (Bonferroni)
  bool pink = false;
  double pink_b = 0;               // 1/f-to-white power ratio at the record's first bin
  double pink_delta_2lnl = 0;      // Whittle likelihood's gain from the 1/f term
  double pink_rms_v = 0;           // the 1/f noise's rms in the filtered residual, volts
  double transfer_error_chi2 = 0;  // χ² along the generic transfer errors (transfer_error_columns)
  bool any() const { return baseline || pink; }
};

// The baseline's filtered columns (volts per unit coefficient) for a record:
// L ∗ {P0..P_degree, cos/sin(2π·h·mains·t), h ≤ harmonics}. They do not
// depend on t (a baseline on v2 does not pass through T): each is computed
// once per problem (Problem::kept_column), shared by its forks and by the
// held-out predictions of one diagnosis (OeRecordShare).
Eigen::MatrixXd baseline_columns(Problem& prob, const Averaged& rec, const std::vector<cd>& t, int degree,
                                 double mains_hz, int harmonics);
// Hum harmonics a record of `seconds` can hold apart from the polynomial
// (h·f·T ≥ ½), at most 3.
int hum_harmonics(double mains_hz, double seconds);

// L ∗ (δT_k·v1) for the generic transfer errors δT_k = T^p·(jωτ)^q, p ≤ 3,
// q ≤ 2: what a bench effect leaves in the residual to second order
// (decide_disturbances measures a baseline beyond them).
Eigen::MatrixXd transfer_error_columns(Problem& prob, const std::vector<cd>& t);

// Decides the disturbance model at transfer t, from the raw (unwhitened)
// filtered residual r (volts), the white noise σ of the filtered residual
// and the channels' white levels. mains_hz: the capture's (0: try 50 and 60).
DisturbanceModel decide_disturbances(Problem& prob, const Averaged& rec, const std::vector<cd>& t,
                                     const Eigen::VectorXd& r, double sigma, double ch1, double ch2,
                                     double sample_rate_hz, double mains_hz);

// The disturbances as the result reports them, at the answer's transfer t:
// the raw filtered residual's coefficients on `columns` (whitened as the fit
// is: `pink` may be null), their sigmas σ·√(s2·(CᵀC)⁺), per shot too.
OeBaseline report_disturbances(const DisturbanceModel& d, const PinkFilter* pink, const Eigen::MatrixXd& columns,
                               Problem& prob, const Averaged& rec, const std::vector<cd>& t, double sigma,
                               double s2);

}  // namespace piezo::update::oe
