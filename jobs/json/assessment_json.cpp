#include "jobs/json/assessment_json.hpp"

#include <cmath>

namespace piezo::jobs {

namespace {
using nlohmann::json;

json vec(const Eigen::VectorXd& v, double scale = 1.0) {
  json a = json::array();
  for (Eigen::Index k = 0; k < v.size(); ++k) a.push_back(v[k] * scale);
  return a;
}

template <class T>
void put(json& j, const char* key, const std::optional<T>& v) {
  if (v) j[key] = *v;
}

json standard_json(const std::optional<dsp::StandardModel>& m,
                   const std::vector<std::string>& shots) {
  json j;
  j["shots"] = shots;
  if (m) {
    j["form"] = m->admittance ? "admittance" : "impedance";
    j["degree"] = m->c.size() - 1;
    j["points"] = m->points;
    j["chi2_reduced"] = m->chi2_reduced;
    j["residual_rel_rms"] = m->residual_rel_rms;
  }
  return j;
}
}  // namespace

json fixture_json(const dsp::FixtureCalibration& f) {
  json j;
  put(j, "fixture_capacitance_f", f.fixture_capacitance_f);
  put(j, "fixture_capacitance_sigma_f", f.fixture_capacitance_sigma_f);
  put(j, "lead_resistance_ohm", f.lead_resistance_ohm);
  put(j, "lead_resistance_sigma_ohm", f.lead_resistance_sigma_ohm);
  put(j, "r1_error", f.r1_error);
  put(j, "r1_error_sigma", f.r1_error_sigma);
  put(j, "skew_s", f.skew_s);
  put(j, "skew_sigma_s", f.skew_sigma_s);
  if (f.skew_s) j["skew_ns"] = *f.skew_s * 1e9;
  put(j, "open_dc_transfer", f.open_dc_transfer);
  put(j, "open_dc_transfer_sigma", f.open_dc_transfer_sigma);
  j["chi2_reduced"] = f.chi2_reduced;
  j["residual_rel_rms"] = f.residual_rel_rms;
  j["converged"] = f.converged;
  j["assumptions"] = f.assumptions;
  return j;
}

json assessment_json(const acq::ImpedanceAssessment& a) {
  json j;
  json c;
  c["applied"] = a.model != dsp::FixtureModel::None;
  c["model"] = std::string(dsp::to_string(a.model));
  c["description"] = a.model_description;
  if (a.calibration) {
    const auto& cal = *a.calibration;
    c["fixture"] = fixture_json(cal.fixture);
    c["standards"] = {{"open", standard_json(cal.open, cal.shots_open)},
                      {"short", standard_json(cal.shrt, cal.shots_short)},
                      {"load", standard_json(cal.load, cal.shots_load)}};
    if (!cal.shots_load.empty()) {
      c["load_ohm"] = cal.load_value.ohm;
      c["load_parallel_f"] = cal.load_value.parallel_f;
    }
    c["notes"] = cal.notes;
  }
  j["compensation"] = c;
  j["deskew"] = {{"applied", a.skew_applied_s != 0.0},
                 {"skew_s", a.skew_applied_s},
                 {"skew_ns", a.skew_applied_s * 1e9},
                 {"source", a.skew_source}};
  if (a.model != dsp::FixtureModel::None || a.skew_applied_s != 0.0) {
    json re = json::array(), im = json::array();
    for (Eigen::Index k = 0; k < a.uncompensated.z_ohm.size(); ++k) {
      re.push_back(a.uncompensated.z_ohm[k].real());
      im.push_back(a.uncompensated.z_ohm[k].imag());
    }
    j["uncompensated"] = {{"re_ohm", re}, {"im_ohm", im}};
  }
  if (a.band) {
    const auto& b = *a.band;
    j["uncertainty"] = {{"source", b.source},
                        {"coverage_factor", b.coverage_factor},
                        {"abs_ohm", vec(b.abs_ohm)},
                        {"abs_sigma_ohm", vec(b.abs_sigma_ohm)},
                        {"phase_deg", vec(b.phase_rad, 180.0 / M_PI)},
                        {"phase_sigma_deg", vec(b.phase_sigma_rad, 180.0 / M_PI)}};
  }
  if (a.kk) {
    const auto& k = *a.kk;
    j["kramers_kronig"] = {{"pass", k.pass},
                           {"causal", k.causal},
                           {"passive", k.passive},
                           {"threshold", k.threshold},
                           {"rms_residual", k.rms_residual},
                           {"rms_residual_z", k.rms_residual_z},
                           {"rms_residual_y", k.rms_residual_y},
                           {"max_residual", k.max_residual},
                           {"max_residual_f_hz", k.max_residual_f_hz},
                           {"max_passivity", k.max_passivity},
                           {"max_passivity_f_hz", k.max_passivity_f_hz},
                           {"pole_pairs", k.pole_pairs},
                           {"residual", vec(k.residual)},
                           {"note", k.note}};
  }
  if (a.validity) {
    json shots = json::array();
    for (std::size_t i = 0; i < a.validity->shots.size(); ++i) {
      const auto& s = a.validity->shots[i];
      json o = {{"name", i < a.shots.size() ? a.shots[i] : std::string()},
                {"clipped", s.clipped},
                {"flags", s.flags}};
      o["coherence"] = std::isfinite(s.coherence) ? json(s.coherence) : json(nullptr);
      o["reconstruction_ratio"] =
          std::isfinite(s.reconstruction_ratio) ? json(s.reconstruction_ratio) : json(nullptr);
      shots.push_back(o);
    }
    j["validity"] = {{"shots", shots},
                     {"low_coherence_fraction", a.validity->low_coherence_fraction},
                     {"coherence_f_hz", vec(a.validity->f_hz)},
                     {"coherence", vec(a.validity->coherence)}};
  }
  if (a.stabilization) {
    json poles = json::array();
    for (const auto& p : a.stabilization->poles)
      poles.push_back({{"order", p.order},
                       {"freq_hz", p.freq_hz},
                       {"damping_ratio", p.damping_ratio},
                       {"stability", dsp::to_string(p.stability)}});
    j["stabilization"] = {{"orders", a.stabilization->orders},
                          {"selected_order", a.stabilization->selected_order},
                          {"poles", poles}};
  }
  j["notes"] = a.notes;
  if (!a.baselines.empty()) {  // per shot: the slow disturbances tested and removed (issue 33)
    auto num = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
    nlohmann::json b = nlohmann::json::array();
    for (std::size_t k = 0; k < a.baselines.size(); ++k) {
      const auto& x = a.baselines[k];
      b.push_back({{"shot", k < a.shots.size() ? a.shots[k] : std::string()},
                   {"tested", x.tested},
                   {"found", x.found},
                   {"removed", x.found && a.baseline_removed},
                   {"delta_chi2", x.delta_chi2},
                   {"dof", x.dof},
                   {"log10_p", x.log10_p},
                   {"chi2_per_dof", num(x.chi2_per_dof)},
                   {"nu", x.nu},
                   {"band_hz", x.band_hz},
                   {"mains_hz", x.mains_hz},
                   {"offset_v", x.offset_v},
                   {"slope_v_per_s", x.slope_v_per_s},
                   {"slope_sigma_v_per_s", num(x.slope_sigma_v_per_s)},
                   {"hum_v", num(x.hum_v)},
                   {"rms_v", x.rms_v},
                   {"note", x.note}});
    }
    j["baseline"] = b;
  }
  return j;
}

}  // namespace piezo::jobs
