#include "impedance_study.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dsp/cross_spectra.hpp"
#include "dsp/fft_ratio.hpp"
#include "dsp/prony_impedance.hpp"
#include "dsp/reference_comparison.hpp"

namespace piezo::study {

namespace {
using clk = std::chrono::steady_clock;

// The scores are dsp/reference_comparison.hpp's (the same as `piezobench model charge`).
dsp::ImpedanceTruth truth_of(const StudyInput& in) {
  dsp::ImpedanceTruth t;
  t.z = in.z_true;
  t.resonances_hz = in.true_resonances_hz;
  t.antiresonances_hz = in.true_antiresonances_hz;
  t.f_lo_hz = in.f_lo_hz;
  t.f_hi_hz = in.f_hi_hz;
  t.peak_exclusion_rel = in.peak_exclusion_rel;
  return t;
}

void score(const StudyInput& in, const dsp::ImpedanceResult& r, StudyRow& row) {
  row.f_hz.assign(r.f_hz.data(), r.f_hz.data() + r.f_hz.size());
  row.z_ohm.assign(r.z_ohm.data(), r.z_ohm.data() + r.z_ohm.size());
  const dsp::TruthComparison c = dsp::compare_to_truth(truth_of(in), r);
  row.ambiguous = c.ambiguous;
  row.res_err_rel = c.res_err_rel;
  row.anti_err_rel = c.anti_err_rel;
  row.max_feature_err_rel = c.max_feature_err_rel;
  row.max_db_err = c.max_db_err;
  row.f_max_db_err = c.f_max_db_err;
  row.median_db_err = c.median_db_err;
}

dsp::DividerRecord record(const StudyInput& in, std::size_t k) {
  return {in.v1[k], in.v2[k], in.sample_rate_hz, in.r1_ohm, in.pretrigger, {}};
}
}  // namespace

StudyRow study_result(const StudyInput& in, const dsp::ImpedanceResult& r, const std::string& method) {
  StudyRow row;
  row.method = method;
  row.samples = r.samples_used;
  if (r.prony) row.order = r.prony->order;
  score(in, r, row);
  return row;
}

bool near_feature(const StudyInput& in, double f) { return dsp::near_true_feature(truth_of(in), f); }

StudyRow study_prony(const StudyInput& in, std::size_t samples, dsp::PronyOptions prony) {
  StudyRow row;
  row.method = "prony";
  dsp::PronyImpedanceOptions o;
  o.prep.max_samples = samples;
  o.prony = prony;
  if (o.prony.band_hz == 0.0) o.prony.band_hz = in.f_hi_hz;
  o.features.fmin_hz = in.f_lo_hz;
  const auto t0 = clk::now();
  const auto r = dsp::impedance_prony(record(in, 0),
                                      dsp::make_grid(in.f_lo_hz, in.f_hi_hz, in.prony_grid_hz), o);
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
                "samples", "order", "resonance err %", "anti-resonance err %", "max dB (at kHz)",
                "median dB");
  s += buf;
  s += "|---|---:|---:|---|---|---:|---:|\n";
  auto errs = [](const std::vector<double>& v) {
    std::string o;
    char b[32];
    for (double e : v) {
      if (std::isfinite(e))
        std::snprintf(b, sizeof b, "%+8.3f ", 100 * e);
      else
        std::snprintf(b, sizeof b, "%8s ", "missing");
      o += b;
    }
    return o;
  };
  for (const auto& r : rows) {
    std::snprintf(
        buf, sizeof buf, "| %-20s | %8zu | %5zu | %-27s | %-27s | %7.3f (%7.1f) | %9.3f |\n",
        r.method.c_str(), r.samples, r.order, errs(r.res_err_rel).c_str(),
        errs(r.anti_err_rel).c_str(), r.max_db_err, r.f_max_db_err / 1e3, r.median_db_err);
    s += buf;
  }
  return s;
}

MethodStats summarize(const std::vector<StudyRow>& runs) {
  MethodStats st;
  if (runs.empty()) return st;
  st.method = runs[0].method;
  st.samples = runs[0].samples;
  st.runs = runs.size();
  auto moments = [&](std::size_t k, bool res, double& mean, double& sd, std::size_t& found) {
    std::vector<double> e;
    for (const auto& r : runs) {
      const auto& v = res ? r.res_err_rel : r.anti_err_rel;
      if (k < v.size() && std::isfinite(v[k])) e.push_back(v[k]);
    }
    found = e.size();
    mean = sd = std::numeric_limits<double>::quiet_NaN();
    if (e.empty()) return;
    mean = 0;
    for (double x : e) mean += x / double(e.size());
    if (e.size() < 2) return;
    sd = 0;
    for (double x : e) sd += (x - mean) * (x - mean) / double(e.size() - 1);
    sd = std::sqrt(sd);
  };
  for (bool res : {true, false}) {
    const std::size_t nf = (res ? runs[0].res_err_rel : runs[0].anti_err_rel).size();
    for (std::size_t k = 0; k < nf; ++k) {
      double m, s;
      std::size_t f;
      moments(k, res, m, s, f);
      (res ? st.res_mean : st.anti_mean).push_back(m);
      (res ? st.res_std : st.anti_std).push_back(s);
      (res ? st.res_found : st.anti_found).push_back(f);
    }
  }
  auto quantile = [](std::vector<double> v, double q) {
    const auto i = static_cast<std::size_t>(q * double(v.size() - 1) + 0.5);
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(i), v.end());
    return v[i];
  };
  std::vector<double> mx, md;
  std::size_t ambiguous = 0, features = 0;
  for (const auto& r : runs) {
    mx.push_back(r.max_db_err);
    md.push_back(r.median_db_err);
    ambiguous += r.ambiguous;
    features += r.res_err_rel.size() + r.anti_err_rel.size();
  }
  st.ambiguous_fraction = features ? double(ambiguous) / double(features) : 0.0;
  st.max_db_median = quantile(mx, 0.5);
  st.max_db_p90 = quantile(mx, 0.9);
  st.median_db_median = quantile(md, 0.5);
  return st;
}

std::string format_stats(const std::vector<MethodStats>& stats) {
  std::string s =
      "| method | samples | runs | resonance err % (mean ± std [found]) | anti-resonance err % "
      "(mean ± std [found]) | ambiguous | max dB median / p90 | median dB |\n"
      "|---|---:|---:|---|---|---:|---:|---:|\n";
  char buf[160];
  auto cells = [&](const std::vector<double>& m, const std::vector<double>& sd,
                   const std::vector<std::size_t>& found, std::size_t runs) {
    std::string o;
    for (std::size_t k = 0; k < m.size(); ++k) {
      if (k) o += ", ";
      if (found[k] == 0) {
        o += "missing";
        continue;
      }
      std::snprintf(buf, sizeof buf, "%+.3f ± %.3f", 100 * m[k], 100 * sd[k]);
      o += buf;
      if (found[k] < runs) o += " [" + std::to_string(found[k]) + "]";  // runs that found it
    }
    return o;
  };
  for (const auto& st : stats) {
    s += "| " + st.method + " | " + std::to_string(st.samples) + " | " + std::to_string(st.runs) +
         " | " + cells(st.res_mean, st.res_std, st.res_found, st.runs) + " | " +
         cells(st.anti_mean, st.anti_std, st.anti_found, st.runs) + " | ";
    std::snprintf(buf, sizeof buf, "%.0f %% | %.2f / %.2f | %.3f |\n", 100 * st.ambiguous_fraction,
                  st.max_db_median, st.max_db_p90, st.median_db_median);
    s += buf;
  }
  return s;
}

}  // namespace piezo::study
