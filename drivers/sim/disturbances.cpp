#include "drivers/sim/disturbances.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <stdexcept>

namespace piezo::drivers::sim {

namespace {

[[noreturn]] void bad(const std::string& what) {
  throw std::invalid_argument("parse_disturbances: " + what);
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

double number(const std::string& key, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v))
    bad("'" + key + "': '" + text + "' is not a number");
  return v;
}

std::string fmt(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

}  // namespace

bool Disturbances::any() const {
  return offset_v != 0.0 || offset_shot_v != 0.0 || hum_v != 0.0 || pink_rel != 0.0 || changes_dut() ||
         jitter_samples != 0.0;
}

void Disturbances::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("Disturbances: ") + what);
  };
  need(std::isfinite(offset_v) && offset_v >= 0, "offset_v must be finite and >= 0");
  need(std::isfinite(offset_shot_v) && offset_shot_v >= 0, "offset_shot_v must be finite and >= 0");
  need(std::isfinite(hum_v) && hum_v >= 0, "hum_v must be finite and >= 0");
  need(mains_hz == 50.0 || mains_hz == 60.0, "mains_hz must be 50 or 60");
  need(std::isfinite(pink_rel) && pink_rel >= 0, "pink_rel must be finite and >= 0");
  // |drift_rel| < 2 keeps every factor 1 ± drift_rel/2 positive.
  need(std::isfinite(drift_rel) && std::abs(drift_rel) < 2, "drift_rel must be in (-2, 2)");
  need(std::isfinite(step_rel) && step_rel > -1, "step_rel must be finite and > -1");
  need(step_after_shot >= 0, "step_after_shot must be >= 0");
  need(std::isfinite(jitter_samples) && jitter_samples >= 0,
       "jitter_samples must be finite and >= 0");
}

Disturbances parse_disturbances(const std::string& text) {
  Disturbances d;
  std::set<std::string> seen;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = text.find(',', pos);
    const std::string item =
        trim(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    pos = comma == std::string::npos ? text.size() + 1 : comma + 1;
    if (item.empty()) continue;
    const auto eq = item.find('=');
    if (eq == std::string::npos) bad("'" + item + "': expected KEY=VALUE");
    const std::string key = trim(item.substr(0, eq)), value = trim(item.substr(eq + 1));
    if (!seen.insert(key).second) bad("'" + key + "' is given twice");
    if (key == "offset" || key == "offset_shot" || key == "hum" || key == "pink" || key == "jitter") {
      const double v = number(key, value);
      if (v < 0) bad("'" + key + "': '" + value + "' must be >= 0");
      if (key == "offset")
        d.offset_v = v;
      else if (key == "offset_shot")
        d.offset_shot_v = v;
      else if (key == "hum")
        d.hum_v = v;
      else if (key == "pink")
        d.pink_rel = v / 100.0;
      else
        d.jitter_samples = v;
    } else if (key == "mains") {
      const double v = number(key, value);
      if (v != 50.0 && v != 60.0) bad("'mains': '" + value + "' must be 50 or 60");
      d.mains_hz = v;
    } else if (key == "drift") {
      const double v = number(key, value);
      if (!(std::abs(v) < 200.0)) bad("'drift': '" + value + "' must be within ±200 (percent)");
      d.drift_rel = v / 100.0;
    } else if (key == "step") {
      const auto at = value.find('@');
      if (at == std::string::npos) bad("'step': '" + value + "': expected PCT@SHOT");
      const std::string pct = value.substr(0, at), shot = value.substr(at + 1);
      const double v = number(key, pct);
      if (!(v > -100.0)) bad("'step': '" + pct + "' must be > -100 (percent)");
      char* end = nullptr;
      const long s = std::strtol(shot.c_str(), &end, 10);
      if (shot.empty() || *end != '\0' || s < 0 || s > 1000000)
        bad("'step': shot '" + shot + "' is not a shot index (an integer >= 0)");
      d.step_rel = v / 100.0;
      d.step_after_shot = static_cast<int>(s);
    } else {
      bad("unknown key '" + key + "' (offset, offset_shot, hum, mains, pink, drift, step, jitter)");
    }
  }
  d.validate();
  return d;
}

std::string to_string(const Disturbances& d) {
  std::string s;
  auto add = [&](const std::string& item) { s += (s.empty() ? "" : ",") + item; };
  if (d.offset_v != 0) add("offset=" + fmt(d.offset_v));
  if (d.offset_shot_v != 0) add("offset_shot=" + fmt(d.offset_shot_v));
  if (d.hum_v != 0) add("hum=" + fmt(d.hum_v) + ",mains=" + fmt(d.mains_hz));
  if (d.pink_rel != 0) add("pink=" + fmt(100.0 * d.pink_rel));
  if (d.drift_rel != 0) add("drift=" + fmt(100.0 * d.drift_rel));
  if (d.step_rel != 0)
    add("step=" + fmt(100.0 * d.step_rel) + "@" + std::to_string(d.step_after_shot));
  if (d.jitter_samples != 0) add("jitter=" + fmt(d.jitter_samples));
  return s;
}

ConstantFactors constant_factors(const Disturbances& d, int shot, int shots) {
  ConstantFactors f;
  if (d.drift_rel != 0 && shots > 0) {
    const double x = shots > 1 ? static_cast<double>(shot) / (shots - 1) - 0.5 : 0.0;
    f.y_e11 = 1.0 + d.drift_rel * x * kDriftSign.y_e11;
    f.eps_t33 = 1.0 + d.drift_rel * x * kDriftSign.eps_t33;
    f.d31 = 1.0 + d.drift_rel * x * kDriftSign.d31;
  }
  if (d.step_rel != 0 && shot > d.step_after_shot) {
    f.eps_t33 *= 1.0 + d.step_rel;
    f.d31 *= 1.0 + d.step_rel;
  }
  return f;
}

TruthNumbers disturbance_truth(const Disturbances& d, double offset_v1, double offset_v2) {
  if (!d.any()) return {};
  return {{"disturbance_offset_v", d.offset_v},
          {"disturbance_offset_v1", offset_v1},
          {"disturbance_offset_v2", offset_v2},
          {"disturbance_hum_v", d.hum_v},
          {"disturbance_mains_hz", d.mains_hz},
          {"disturbance_pink_rel", d.pink_rel},
          {"disturbance_drift_rel", d.drift_rel},
          {"disturbance_drift_sign_YE11", kDriftSign.y_e11},
          {"disturbance_drift_sign_epsT33", kDriftSign.eps_t33},
          {"disturbance_drift_sign_d31", kDriftSign.d31},
          {"disturbance_step_rel", d.step_rel},
          {"disturbance_step_after_shot", static_cast<double>(d.step_after_shot)},
          {"disturbance_jitter_samples", d.jitter_samples}};
}

TruthSeries disturbance_series(const std::vector<ShotDisturbances>& shots) {
  TruthSeries s = {
      {"disturbance_shot_hum_phase_v1_rad", {}}, {"disturbance_shot_hum_phase_v2_rad", {}},
      {"disturbance_shot_YE11_factor", {}},      {"disturbance_shot_epsT33_factor", {}},
      {"disturbance_shot_d31_factor", {}},       {"disturbance_shot_jitter_samples", {}}};
  for (const auto& x : shots) {
    s[0].second.push_back(x.hum_phase_rad[0]);
    s[1].second.push_back(x.hum_phase_rad[1]);
    s[2].second.push_back(x.factors.y_e11);
    s[3].second.push_back(x.factors.eps_t33);
    s[4].second.push_back(x.factors.d31);
    s[5].second.push_back(x.jitter_samples);
  }
  return s;
}

double mains_waveform(double t, double mains_hz, double phase_rad) {
  const double th = 2.0 * M_PI * mains_hz * t + phase_rad;
  return std::sin(th) + 0.30 * std::sin(2.0 * th) + 0.15 * std::sin(3.0 * th);
}

std::vector<double> pink_noise(std::size_t n, std::mt19937_64& rng) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  // Two rows more than the record needs: the 1/f then reaches two octaves
  // below the record's lowest frequency, so even the lowest bins of a record
  // lie on it (with only log2(n) rows they flatten: slope −0.88 measured).
  int rows = 1;
  while ((std::size_t{1} << rows) < n) ++rows;
  rows += 2;
  std::vector<double> row(static_cast<std::size_t>(rows));
  double sum = 0.0;
  for (double& r : row) sum += (r = gauss(rng));     // each row starts stationary
  const double scale = 1.0 / std::sqrt(rows + 1.0);  // rows + white term, unit variance each
  std::vector<double> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    const auto r = static_cast<std::size_t>(std::countr_zero(static_cast<std::uint64_t>(k + 1)));
    if (r < row.size()) {
      sum -= row[r];
      row[r] = gauss(rng);
      sum += row[r];
    }
    out[k] = scale * (sum + gauss(rng));
  }
  return out;
}

}  // namespace piezo::drivers::sim
