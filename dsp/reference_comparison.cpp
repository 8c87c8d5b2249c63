#include "dsp/reference_comparison.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "dsp/features.hpp"

namespace piezo::dsp {

namespace {

std::vector<double> match(const std::vector<double>& truth, const std::vector<Feature>& found,
                          std::size_t& ambiguous) {
  std::vector<double> out;
  for (double t : truth) {
    double best = std::numeric_limits<double>::quiet_NaN(), dist = 0.03 * t;
    std::size_t candidates = 0;
    for (const auto& f : found) {
      if (std::abs(f.extremum_hz - t) < 0.03 * t) ++candidates;
      if (std::abs(f.extremum_hz - t) < dist) {
        dist = std::abs(f.extremum_hz - t);
        best = (f.extremum_hz - t) / t;
      }
    }
    ambiguous += candidates > 1;
    out.push_back(best);
  }
  return out;
}

}  // namespace

ImpedanceTruth impedance_truth(std::function<std::complex<double>(double)> z, double f_lo_hz, double f_hi_hz,
                               double step_hz) {
  ImpedanceTruth t;
  t.z = std::move(z);
  t.f_lo_hz = f_lo_hz;
  t.f_hi_hz = f_hi_hz;
  const auto found = find_features(t.z, f_lo_hz, f_hi_hz, step_hz);
  for (const auto& f : found.resonances) t.resonances_hz.push_back(f.f_hz);
  for (const auto& f : found.antiresonances) t.antiresonances_hz.push_back(f.f_hz);
  return t;
}

bool near_true_feature(const ImpedanceTruth& truth, double f) {
  for (const auto* v : {&truth.resonances_hz, &truth.antiresonances_hz})
    for (double t : *v)
      if (std::abs(f - t) <= truth.peak_exclusion_rel * t) return true;
  return false;
}

TruthComparison compare_to_truth(const ImpedanceTruth& truth, const ImpedanceResult& r) {
  TruthComparison c;
  c.res_err_rel = match(truth.resonances_hz, r.features.resonances, c.ambiguous);
  c.anti_err_rel = match(truth.antiresonances_hz, r.features.antiresonances, c.ambiguous);
  for (const auto* v : {&c.res_err_rel, &c.anti_err_rel})
    for (double e : *v)
      c.max_feature_err_rel = std::isfinite(e) ? std::max(c.max_feature_err_rel, std::abs(e))
                                               : std::numeric_limits<double>::infinity();
  std::vector<double> err;
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
    const double f = r.f_hz[k];
    if (f < truth.f_lo_hz || f > truth.f_hi_hz) continue;
    if (near_true_feature(truth, f)) continue;
    err.push_back(std::abs(20.0 * std::log10(std::abs(r.z_ohm[k]) / std::abs(truth.z(f)))));
    if (err.back() > c.max_db_err) {
      c.max_db_err = err.back();
      c.f_max_db_err = f;
    }
  }
  c.scored = err.size();
  if (err.empty()) return c;
  std::nth_element(err.begin(), err.begin() + static_cast<std::ptrdiff_t>(err.size() / 2), err.end());
  c.median_db_err = err[err.size() / 2];
  return c;
}

}  // namespace piezo::dsp
