#include "impedance_study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"

namespace piezo::study {

namespace {
using clk = std::chrono::steady_clock;
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> match(const std::vector<double>& truth, const std::vector<dsp::Feature>& found) {
  std::vector<double> out;
  for (double t : truth) {
    double best = std::numeric_limits<double>::quiet_NaN(), dist = 0.03 * t;
    // The study compares |Z| extrema (what every method can report) with the true extrema.
    for (const auto& f : found)
      if (std::abs(f.extremum_hz - t) < dist) { dist = std::abs(f.extremum_hz - t); best = (f.extremum_hz - t) / t; }
    out.push_back(best);
  }
  return out;
}

void score(const StudyInput& in, const dsp::ImpedanceResult& r, StudyRow& row) {
  row.res_err_rel = match(in.true_resonances_hz, r.features.resonances);
  row.anti_err_rel = match(in.true_antiresonances_hz, r.features.antiresonances);
  row.max_feature_err_rel = 0;
  for (const auto* v : {&row.res_err_rel, &row.anti_err_rel})
    for (double e : *v) row.max_feature_err_rel = std::isfinite(e) ? std::max(row.max_feature_err_rel, std::abs(e)) : kInf;
  std::vector<double> err;
  for (Eigen::Index k = 0; k < r.f_hz.size(); ++k) {
    const double f = r.f_hz[k];
    if (f < in.f_lo_hz || f > in.f_hi_hz) continue;
    bool near = false;
    for (const auto* v : {&in.true_resonances_hz, &in.true_antiresonances_hz})
      for (double t : *v) near = near || std::abs(f - t) <= in.peak_exclusion_rel * t;
    if (near) continue;
    err.push_back(std::abs(20.0 * std::log10(std::abs(r.z_ohm[k]) / std::abs(in.z_true(f)))));
    if (err.back() > row.max_db_err) {
      row.max_db_err = err.back();
      row.f_max_db_err = f;
    }
  }
  if (err.empty()) return;
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  row.median_db_err = err[err.size() / 2];
}

dsp::DividerRecord record(const StudyInput& in, std::size_t k) {
  return {in.v1[k], in.v2[k], in.sample_rate_hz, in.r1_ohm, in.pretrigger, {}};
}
}  // namespace

StudyRow study_prony(const StudyInput& in, std::size_t samples) {
  StudyRow row;
  row.method = "prony";
  dsp::PronyImpedanceOptions o;
  o.prep.max_samples = samples;
  o.prony.band_hz = in.f_hi_hz;
  o.features.fmin_hz = in.f_lo_hz;
  const auto t0 = clk::now();
  const auto r = dsp::impedance_prony(record(in, 0), dsp::make_grid(in.f_lo_hz, in.f_hi_hz, in.prony_grid_hz), o);
  row.elapsed_ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
  row.samples = r.samples_used;
  row.order = r.prony->order;
  score(in, r, row);
  return row;
}

StudyRow study_fft(const StudyInput& in, bool difference) {
  StudyRow row;
  row.method = difference ? "fft diff" : "fft raw";
  dsp::FftRatioOptions o;
  o.difference = difference;
  o.fmax_hz = 2 * in.f_hi_hz;
  o.features.fmin_hz = in.f_lo_hz;
  const auto t0 = clk::now();
  const auto r = dsp::impedance_fft(record(in, 0), o);
  row.elapsed_ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
  row.samples = r.samples_used;
  score(in, r, row);
  return row;
}

StudyRow study_xspec(const StudyInput& in, std::size_t segment, bool difference) {
  StudyRow row;
  std::vector<dsp::DividerRecord> recs;
  for (std::size_t k = 0; k < in.v1.size(); ++k) recs.push_back(record(in, k));
  dsp::CrossSpectraOptions o;
  o.segment = segment;
  o.overlap = 0.0;
  o.difference = difference;
  o.window = {dsp::WindowKind::Rectangular, 0};  // one transient per record, from t = 0
  o.fmax_hz = 2 * in.f_hi_hz;
  o.features.fmin_hz = in.f_lo_hz;
  const auto t0 = clk::now();
  const auto r = dsp::impedance_xspec(recs, o);
  row.elapsed_ms = std::chrono::duration<double, std::milli>(clk::now() - t0).count();
  row.method = r.method + (difference ? " diff x" : " raw x") + std::to_string(recs.size());
  row.samples = r.samples_used;
  score(in, r, row);
  return row;
}

std::string format_table(const std::vector<StudyRow>& rows) {
  std::string s;
  char buf[512];
  std::snprintf(buf, sizeof buf, "| %-20s | %8s | %5s | %-27s | %-27s | %18s | %9s |\n", "method",
                "samples", "order", "resonance err %", "anti-resonance err %",
                "max dB (at kHz)", "median dB");
  s += buf;
  auto errs = [](const std::vector<double>& v) {
    std::string o;
    char b[32];
    for (double e : v) {
      if (std::isfinite(e)) std::snprintf(b, sizeof b, "%+8.3f ", 100 * e);
      else std::snprintf(b, sizeof b, "%8s ", "missing");
      o += b;
    }
    return o;
  };
  for (const auto& r : rows) {
    std::snprintf(buf, sizeof buf, "| %-20s | %8zu | %5zu | %-27s | %-27s | %7.3f (%7.1f) | %9.3f |\n",
                  r.method.c_str(), r.samples, r.order, errs(r.res_err_rel).c_str(),
                  errs(r.anti_err_rel).c_str(), r.max_db_err, r.f_max_db_err / 1e3, r.median_db_err);
    s += buf;
  }
  return s;
}

}  // namespace piezo::study
