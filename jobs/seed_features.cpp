// The jobs' room (jobs/): the seed chain's features of a capture (see seed_features.hpp).
#include "jobs/seed_features.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "jobs/json/output_error_json.hpp"
#include "model/material.hpp"

namespace piezo::jobs {

namespace {
std::string fmt(const char* f, double a) {
  char b[96];
  std::snprintf(b, sizeof b, f, a);
  return b;
}
}  // namespace

dsp::DriveBand capture_drive_band(const acq::Capture& cap, const std::vector<std::string>& shots) {
  const acq::Shot* first = nullptr;
  std::vector<double> v1;
  int n = 0;
  for (const auto& s : cap.shots) {
    if (s.role != acq::Role::Dut || s.excitation == acq::Excitation::Sine) continue;
    if (!shots.empty() && std::find(shots.begin(), shots.end(), s.name) == shots.end()) continue;
    if (!first) {
      first = &s;
      v1 = s.v1;
      n = 1;
      continue;
    }
    if (s.samples() != first->samples() || s.sample_rate_hz != first->sample_rate_hz ||
        s.pretrigger_samples != first->pretrigger_samples || s.excitation != first->excitation)
      continue;
    for (std::size_t i = 0; i < v1.size(); ++i) v1[i] += s.v1[i];
    ++n;
  }
  if (!first) throw std::invalid_argument("the capture holds no transient \"dut\" shot");
  for (double& x : v1) x /= n;
  return dsp::drive_band(v1, first->sample_rate_hz,
                         static_cast<std::size_t>(std::max<std::int64_t>(0, first->pretrigger_samples)));
}

void widen_by_order_spread(dsp::ImpedanceFeatures& f, const std::vector<dsp::ImpedanceFeatures>& others) {
  auto widen = [&](std::vector<dsp::Feature>& mine, auto member) {
    for (auto& x : mine) {
      double d = 0;
      for (const auto& o : others) {
        double best = INFINITY;
        for (const auto& y : o.*member)
          if (std::abs(y.f_hz / x.f_hz - 1) < 0.03) best = std::min(best, std::abs(y.f_hz - x.f_hz));
        if (std::isfinite(best)) d = std::max(d, best);
      }
      if (std::isfinite(x.sigma_hz)) x.sigma_hz = std::hypot(x.sigma_hz, d);
    }
  };
  widen(f.resonances, &dsp::ImpedanceFeatures::resonances);
  widen(f.antiresonances, &dsp::ImpedanceFeatures::antiresonances);
  double dc = 0;
  for (const auto& o : others)
    if (std::isfinite(o.capacitance_f)) dc = std::max(dc, std::abs(o.capacitance_f - f.capacitance_f));
  if (std::isfinite(f.capacitance_sigma_f)) f.capacitance_sigma_f = std::hypot(f.capacitance_sigma_f, dc);
}

SeedFeatures select_seed_features(const dsp::ImpedanceFeatures& z, double estimate_hi_hz, const dsp::DriveBand& drive,
                                  const CaptureModel& cm) {
  SeedFeatures sf;
  sf.drive = drive;
  const auto f0 = update::model_frequencies(*cm.solver, cm.cls.e_form(cm.p0), 3, 3, update::CmcmOptions{}.modal);
  double mlo = INFINITY, mhi = 0;
  for (double f : f0.resonances_hz) mlo = std::min(mlo, f), mhi = std::max(mhi, f);
  for (double f : f0.antiresonances_hz) mlo = std::min(mlo, f), mhi = std::max(mhi, f);
  sf.model_lo_hz = mlo / kModelRange;
  sf.model_hi_hz = mhi * kModelRange;
  auto& b = sf.band;
  b.lo_hz = sf.model_lo_hz;
  b.hi_hz = sf.model_hi_hz;
  std::string lo_src = "the model's mode range", hi_src = "the model's mode range";
  if (drive.found && drive.lo_hz > b.lo_hz) b.lo_hz = drive.lo_hz, lo_src = "the drive's band";
  if (drive.found && drive.hi_hz < b.hi_hz) b.hi_hz = drive.hi_hz, hi_src = "the drive's band";
  if (estimate_hi_hz > 0 && estimate_hi_hz < b.hi_hz) b.hi_hz = estimate_hi_hz, hi_src = "the estimate's band";
  if (!drive.found) b.hi_hz = b.lo_hz;  // no bin of the drive above its noise: an empty band
  b.source = "low edge: " + lo_src + ", high edge: " + hi_src;

  nlohmann::json dropped = nlohmann::json::array();
  auto take = [&](const std::vector<dsp::Feature>& in, const char* what, std::vector<double>& f,
                  std::vector<double>& s) {
    for (const auto& x : in) {
      if (!std::isfinite(x.f_hz)) continue;
      std::string why;
      if (!b.contains(x.f_hz)) why = "outside the band";
      else if (!(std::isfinite(x.sigma_hz) && x.sigma_hz > 0)) why = "no sigma";
      else if (f.size() >= 3) why = "beyond the three the model pairs";
      if (!why.empty()) {
        dropped.push_back({{"kind", what}, {"f_hz", x.f_hz}, {"sigma_hz", x.sigma_hz}, {"why", why}});
        continue;
      }
      f.push_back(x.f_hz);
      s.push_back(x.sigma_hz);
    }
  };
  auto& mf = sf.features;
  take(z.resonances, "resonance", mf.resonances_hz, mf.resonance_sigma_hz);
  take(z.antiresonances, "antiresonance", mf.antiresonances_hz, mf.antiresonance_sigma_hz);
  if (z.capacitance_f > 0 && std::isfinite(z.capacitance_f)) {
    mf.low_z_hz = 400.0;  // the seed's low-frequency point (Tables 4/5)
    mf.low_z_ohm = 1.0 / (2 * M_PI * mf.low_z_hz * z.capacitance_f);
    if (std::isfinite(z.capacitance_sigma_f) && z.capacitance_sigma_f > 0)
      mf.low_z_sigma_ohm = mf.low_z_ohm * z.capacitance_sigma_f / z.capacitance_f;
  }
  if (mf.resonances_hz.empty() && mf.antiresonances_hz.empty()) {
    sf.no_features = "no resonance or anti-resonance with a sigma in " + fmt("%.4g", b.lo_hz) + "-" +
                     fmt("%.4g Hz", b.hi_hz) + " (" + b.source + "; the drive: " + drive.note + "); " +
                     std::to_string(dropped.size()) + " found outside it or without sigma";
  }
  sf.json = {{"resonances_hz", mf.resonances_hz},
             {"resonances_sigma_hz", mf.resonance_sigma_hz},
             {"antiresonances_hz", mf.antiresonances_hz},
             {"antiresonances_sigma_hz", mf.antiresonance_sigma_hz},
             {"low_z_ohm", mf.low_z_ohm},
             {"low_z_hz", mf.low_z_hz},
             {"low_z_sigma_ohm", mf.low_z_sigma_ohm},
             {"capacitance_f", z.capacitance_f},
             {"capacitance_sigma_f", z.capacitance_sigma_f},
             {"band",
              {{"lo_hz", b.lo_hz},
               {"hi_hz", b.hi_hz},
               {"source", b.source},
               {"drive", {{"found", drive.found}, {"lo_hz", drive.lo_hz}, {"hi_hz", drive.hi_hz}, {"note", drive.note}}},
               {"model_range_hz", {sf.model_lo_hz, sf.model_hi_hz}}}},
             {"dropped", dropped}};
  return sf;
}

nlohmann::json feature_update_json(const update::FeatureUpdate& u, const SeedFeatures& sf) {
  nlohmann::json params = nlohmann::json::array();
  for (const auto& c : u.check.constants)
    params.push_back({{"name", c.name},
                      {"unit", c.unit},
                      {"value", c.value},
                      {"sigma", std::isfinite(c.sigma) ? nlohmann::json(c.sigma) : nlohmann::json(nullptr)},
                      {"sigma_statistical",
                       std::isfinite(c.sigma_statistical) ? nlohmann::json(c.sigma_statistical) : nlohmann::json(nullptr)},
                      {"relative_sigma", std::isfinite(c.sigma) ? nlohmann::json(std::abs(c.sigma / c.value))
                                                                : nlohmann::json(nullptr)},
                      {"status", c.status},
                      {"reason", c.reason},
                      {"note", c.note}});
  nlohmann::json res = nlohmann::json::array();
  for (const auto& r : u.check.residuals)
    res.push_back({{"kind", r.kind}, {"index", r.index}, {"measured", r.measured}, {"sigma", r.sigma},
                   {"model", r.model}, {"z", r.z}});
  nlohmann::json j = {{"method", update::to_string(u.method)},
                      {"converged", u.ok()},
                      {"status", u.check.status},
                      {"message", u.check.reason},
                      {"reason", u.check.reason},
                      {"method_status", u.method_status},
                      {"method_message", u.method_message},
                      {"updated", tube_params_json(u.updated)},
                      {"parameters", params},
                      {"features", sf.json},
                      {"residuals", res},
                      {"chi2", u.check.chi2},
                      {"dof", u.check.dof},
                      {"log10_chance", u.check.log10_chance},
                      {"birge", u.check.birge},
                      {"seconds", u.seconds}};
  if (u.eps_t33_from_c > 0)
    j["eps_t33_from_capacitance"] = {{"epsT33_rel", u.eps_t33_from_c / model::kEps0},
                                     {"sigma", u.eps_t33_from_c_sigma / model::kEps0}};
  if (u.method == update::FeatureMethod::cmcm)
    j["sigma_resolves"] = {{"done", u.resolves}, {"failed", u.resolves_failed}};
  return j;
}

}  // namespace piezo::jobs
