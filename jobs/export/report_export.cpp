#include "jobs/export/report_export.hpp"

#include "jobs/json/mode_figures_json.hpp"
#include "jobs/json/output_error_json.hpp"
#include "jobs/json/json_text.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "dsp/impedance_io.hpp"

namespace piezo::jobs {

namespace {
const Curve& measured(const PipelineResult& r) {
  if (r.curves.empty()) throw std::runtime_error("export: no impedance estimate in this result");
  return r.curves.front();  // the Prony-SS estimate the update used
}

dsp::ImpedanceResult as_impedance(const Curve& c) {
  dsp::ImpedanceResult z;
  z.method = c.label;
  z.f_hz = Eigen::Map<const Eigen::VectorXd>(c.f_hz.data(), static_cast<Eigen::Index>(c.f_hz.size()));
  z.z_ohm = Eigen::Map<const Eigen::VectorXcd>(c.z_ohm.data(), static_cast<Eigen::Index>(c.z_ohm.size()));
  return z;
}

std::ofstream open_out(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("export: cannot write " + path);
  return f;
}
}  // namespace

void export_csv(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  dsp::write_impedance_csv(f, as_impedance(measured(r)));
}

void export_touchstone(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  dsp::write_touchstone_s1p(f, as_impedance(measured(r)), 50.0);
}

nlohmann::json report_json(const PipelineResult& r) {
  nlohmann::json j;
  j["capture"] = r.capture_path;
  j["shots"] = r.shots;
  j["shots_averaged"] = r.shots_averaged;
  j["awg_idn"] = r.awg_idn;
  j["daq_idn"] = r.daq_idn;
  j["resonances_hz"] = r.resonances_hz;
  j["antiresonances_hz"] = r.antiresonances_hz;
  j["order"] = r.order;
  j["update_method"] = r.update_method;
  j["parameters"] = nlohmann::json::array();
  for (const auto& p : r.params) {
    nlohmann::json row = {{"name", p.name}, {"unit", p.unit}, {"original", p.original}, {"updated", p.updated}};
    if (p.sigma) row["sigma"] = *p.sigma;
    if (!p.status.empty()) row["status"] = p.status;
    if (p.truth) row["true"] = *p.truth;
    if (p.cmcm) row["cmcm"] = *p.cmcm;
    if (p.lm) row["lm"] = *p.lm;
    if (p.oe) row["output_error"] = {{"value", *p.oe}, {"sigma", p.oe_sigma.value_or(NAN)}, {"status", p.oe_status}};
    if (p.uncorrected)  // the update's own constants, without the effect the diagnosis named
      row["uncorrected"] = {{"value", *p.uncorrected},
                            {"sigma", p.uncorrected_sigma ? nlohmann::json(*p.uncorrected_sigma) : nlohmann::json(nullptr)},
                            {"status", p.uncorrected_status}};
    j["parameters"].push_back(row);
  }
  if (r.corrected) {  // the parameters' "updated" are the constants refitted with this effect
    const auto& c = *r.corrected;
    j["corrected_for"] = {{"effect", c.effect},
                          {"unit", c.unit},
                          {"value", c.value},
                          {"sigma", c.sigma},
                          {"heldout_shrink", c.heldout_shrink ? nlohmann::json(*c.heldout_shrink) : nlohmann::json(nullptr)},
                          {"heldout_without_gap", c.heldout_without_gap},
                          {"source", c.source},
                          {"label", c.label}};
  } else {
    j["corrected_for"] = nullptr;
  }
  j["stages"] = nlohmann::json::array();
  for (const auto& s : r.stages) j["stages"].push_back({{"name", s.name}, {"ran", s.ran}, {"note", s.note}});
  {  // the work done (issue 43): totals, then per phase of the run
    WorkCounts t;
    nlohmann::json phases = nlohmann::json::array();
    for (const auto& p : r.work) {
      t += p.work;
      phases.push_back({{"phase", p.phase},
                        {"modal_solves", p.work.modal_solves},
                        {"prony_decompositions", p.work.prony_decompositions},
                        {"ffts", p.work.ffts},
                        {"reduced_port_models", p.work.reduced_port_models},
                        {"seconds", p.seconds}});
    }
    j["work"] = {{"modal_solves", t.modal_solves},
                 {"prony_decompositions", t.prony_decompositions},
                 {"ffts", t.ffts},
                 {"reduced_port_models", t.reduced_port_models},
                 {"phases", phases}};
  }
  j["verdict"] = r.verdict;
  if (r.fixture) {  // measured from the capture's calibration shots
    const auto& f = *r.fixture;
    auto o = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
    j["fixture"] = {{"model", r.fixture_model},
                    {"fixture_capacitance_f", o(f.fixture_capacitance_f)},
                    {"lead_resistance_ohm", o(f.lead_resistance_ohm)},
                    {"r1_error", o(f.r1_error)},
                    {"skew_s", o(f.skew_s)}};
  }
  if (r.mode_figures) {  // the per-mode figures: the updated model's, else the Prony-SS estimate's
    const auto& m = *r.mode_figures;
    if (m.error.empty()) {
      j["modes"] = modes_json(m.figures);
      j["mode_summary"] = mode_summary_json(m.figures, m.mean_diameter_m, m.mean_diameter_source);
    } else {
      j["modes"] = nlohmann::json::array();
      j["mode_summary"] = {{"notes", {"no mode figures: " + m.error}}};
    }
    j["mode_summary"]["estimate"] = "Prony-SS (the pipeline's estimate, before any fixture correction)";
    j["mode_summary"]["source"] = m.source;
  }
  if (r.output_error) j["output_error"] = output_error_json(*r.output_error, r.output_error_excitation);
  if (r.diagnosis) j["diagnosis"] = diagnosis_json(*r.diagnosis);
  j["warnings"] = r.warnings;
  if (!r.damping_from_resonances.empty()) j["damping_from_resonances"] = r.damping_from_resonances;
  return j;
}

void export_json(const PipelineResult& r, const std::string& path) {
  auto f = open_out(path);
  f << json_text(report_json(r), 2) << "\n";
}

nlohmann::json diagnosis_json(const update::GapDiagnosis& d) {
  auto opt = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  // Issue 7's interface: gap_before, noise_floor, regions, effects (name,
  // params, gap_after, shrink, holdout_shrink, significant, aliases), verdict
  // {effect, holdout_shrink}. Gaps are √(χ²/dof): 1 = at the measured noise;
  // noise_floor is the largest gap still reported as "no gap" for this dof.
  const double dof = std::max(1, d.dof_fit);
  j["gap_before"] = d.gap_fit;
  j["noise_floor"] = std::sqrt(1.0 + std::max(3.0 * std::sqrt(2.0 / dof), 0.3));
  j["verdict"] = {{"effect", d.verdict_effect},
                  {"holdout_shrink", opt(d.heldout_shrink)},
                  {"alternatives", d.verdict_alternatives},
                  {"heldout_without_gap", d.heldout_without_gap},
                  {"base_from_other_start", d.base_from_other_start},
                  {"text", d.verdict}};
  j["verdict_text"] = d.verdict;
  j["disturbances"] = d.disturbances;
  j["verdict_effect"] = d.verdict_effect;
  j["measured"] = nlohmann::json::array();
  for (const auto& m : d.measured)
    j["measured"].push_back({{"name", m.name}, {"value", m.value}, {"sigma", m.sigma}, {"source", m.source}});
  j["method"] = d.method;
  j["gap"] = d.gap;
  j["gap_fit"] = d.gap_fit;
  j["chi2_fit"] = d.chi2_fit;
  j["n_fit"] = d.n_fit;
  j["gap_heldout"] = opt(d.gap_heldout);
  j["chi2_heldout"] = opt(d.chi2_heldout);
  j["n_heldout"] = d.n_heldout;
  j["heldout_shrink"] = opt(d.heldout_shrink);
  j["fit_data"] = d.fit_description;
  j["heldout_data"] = d.heldout_description;
  j["added"] = d.added;
  j["material_base"] = {{"YE11", d.material_base.y_e11}, {"nu12", d.material_base.nu12}, {"d31", d.material_base.d31},
                        {"epsT33_rel", d.material_base.eps_t33 / model::kEps0}};
  j["regions"] = nlohmann::json::array();
  for (const auto& g : d.regions) {
    nlohmann::json rj = {{"name", g.name}, {"f_lo_hz", g.f_lo_hz}, {"f_hi_hz", g.f_hi_hz}, {"points", g.points},
                         {"chi2", g.chi2}, {"share", g.share}, {"kind", g.kind}, {"shift_pct", g.shift_pct},
                         {"width_pct", g.width_pct}, {"level_db", g.level_db}, {"phase_deg", g.phase_deg}};
    if (!g.description.empty()) {  // the output-error diagnosis's regions
      rj["description"] = g.description;
      rj["log10_p"] = g.log10_p;
      rj["delay_s"] = g.delay_s;
      rj["resonance"] = nullptr;
      if (g.resonance)
        rj["resonance"] = {{"f_hz", g.resonance->f_hz}, {"q", g.resonance->q}, {"k_eff", g.resonance->k_eff},
                           {"c_f", g.resonance->c_f}, {"delta_chi2", g.resonance->delta_chi2},
                           {"q_resolved", g.resonance->q_resolved}, {"q_min", g.resonance->q_min}};
    }
    j["regions"].push_back(rj);
  }
  auto eff = [&](const update::EffectReport& e) {
    nlohmann::json r = {{"name", e.name}, {"unit", e.unit}, {"alias", e.alias}, {"alias_residual", e.alias_residual},
                        {"detectability", e.detectability}, {"typical", e.typical},
                        {"alias_bias_pct", {{"YE11", e.bias_y_e11_pct}, {"nu12", e.bias_nu12_pct},
                                            {"d31", e.bias_d31_pct}, {"epsT33", e.bias_eps_t33_pct}}}};
    // What the alias mimics: the constants a typical magnitude would move (> 0.01 %).
    r["aliases"] = nlohmann::json::array();
    if (e.alias) {
      const std::pair<const char*, double> b[] = {
          {"YE11", e.bias_y_e11_pct}, {"nu12", e.bias_nu12_pct}, {"d31", e.bias_d31_pct}, {"epsT33", e.bias_eps_t33_pct}};
      for (const auto& [n, v] : b)
        if (std::abs(v) > 0.01) r["aliases"].push_back(n);
    }
    r["indistinguishable_from"] = e.indistinguishable_from;
    r["params"] = nlohmann::json::object();
    r["gap_after"] = nullptr;
    r["shrink"] = nullptr;
    r["holdout_shrink"] = nullptr;
    r["significant"] = false;
    if (e.fitted) {
      r["params"][e.name] = e.value;
      r["gap_after"] = std::sqrt(e.chi2_after / std::max(1, d.dof_fit - 1));
      r["shrink"] = e.shrink_fit;
      r["holdout_shrink"] = opt(e.heldout_shrink);
      r["value"] = e.value;
      r["sigma"] = e.sigma;
      r["chi2_after"] = e.chi2_after;
      r["delta_chi2"] = e.delta_chi2;
      r["shrink_fit"] = e.shrink_fit;
      r["significant"] = e.significant;
      r["heldout_shrink"] = opt(e.heldout_shrink);
    }
    if (!e.note.empty()) r["note"] = e.note;
    return r;
  };
  j["effects"] = nlohmann::json::array();
  for (const auto& e : d.effects) j["effects"].push_back(eff(e));
  j["steps"] = nlohmann::json::array();
  for (const auto& e : d.steps) j["steps"].push_back(eff(e));
  j["seconds"] = d.seconds;
  return j;
}

}  // namespace piezo::jobs
