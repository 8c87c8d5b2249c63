#include "jobs/json/output_error_json.hpp"

#include <cmath>

#include "model/material.hpp"

namespace piezo::jobs {

nlohmann::json tube_params_json(const update::TubeParams& p) {
  return {{"YE11", p.y_e11}, {"nu12", p.nu12}, {"d31", p.d31}, {"epsT33_rel", p.eps_t33 / model::kEps0}};
}

namespace {
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }
}  // namespace

nlohmann::json baseline_json(const update::OeBaseline& b) {
  nlohmann::json shots = nlohmann::json::array();
  for (const auto& s : b.shots)
    shots.push_back({{"shot", s.shot},
                     {"offset_v", number(s.offset_v)},
                     {"slope_v_per_s", number(s.slope_v_per_s)},
                     {"hum_v", number(s.hum_v)}});
  nlohmann::json channels = nlohmann::json::array();
  if (b.channel_offsets)
    for (int c = 0; c < 2; ++c)
      channels.push_back({{"channel", c + 1},
                          {"offset_v", b.channel_offset_v[c]},
                          {"offset_sigma_v", b.channel_offset_sigma_v[c]},
                          {"source", "pretrigger mean"}});
  return {{"modelled", b.modelled},
          {"delta_chi2", b.delta_chi2},
          {"transfer_error_chi2", b.transfer_error_chi2},
          {"dof", b.dof},
          {"log10_p", b.log10_p},
          {"poly_degree", b.poly_degree},
          {"mains_hz", b.mains_hz},
          {"mains_known", b.mains_known},
          {"mains_distinguishable", b.mains_distinguishable},
          {"harmonics", b.harmonics},
          {"differential",
           {{"what", "channel 1 minus channel 2, as the output error sees them"},
            {"offset_v", number(b.offset_v)},
            {"offset_sigma_v", number(b.offset_sigma_v)},
            {"slope_v_per_s", number(b.slope_v_per_s)},
            {"slope_sigma_v_per_s", number(b.slope_sigma_v_per_s)},
            {"hum_v", number(b.hum_v)},
            {"hum_sigma_v", number(b.hum_sigma_v)}}},
          {"channels", channels},
          {"pink",
           {{"modelled", b.pink},
            {"ratio_at_first_bin", b.pink_ratio},
            {"rms_v", b.pink_rms_v},
            {"delta_2lnl", b.pink_delta_2lnl}}},
          {"shots", shots}};
}

nlohmann::json shot_consistency_json(const update::OeShotConsistency& c) {
  nlohmann::json changes = nlohmann::json::array();
  for (const auto& ch : c.changes) {
    changes.push_back({{"parameter", ch.parameter},
                       {"kind", ch.kind},
                       {"size_pct", ch.size_pct},
                       {"sigma_pct", ch.sigma_pct},
                       {"z", ch.z}});
    if (ch.kind == "step") changes.back()["after_shot"] = ch.after_shot;
  }
  return {{"tested", c.tested},
          {"shots", c.shots},
          {"chi2", c.chi2},
          {"dof", c.dof},
          {"log10_p", c.log10_p},
          {"consistent", c.consistent},
          {"per_shot_pct", c.per_shot_pct},
          {"per_shot_sigma_pct", c.per_shot_sigma_pct},
          {"changes", changes},
          {"summary", c.summary},
          {"jitter_samples", c.jitter_samples},
          {"aligned", c.aligned}};
}

nlohmann::json output_error_json(const update::OeResult& r, const std::string& excitation) {
  nlohmann::json params = nlohmann::json::array();
  std::vector<std::string> names;
  for (const auto& p : r.parameters) {
    params.push_back({{"name", p.name}, {"unit", p.unit}, {"value", p.value}, {"sigma", p.sigma},
                      {"relative_sigma", std::abs(p.sigma / p.value)}, {"nominal", p.nominal},
                      {"sigma_statistical", p.sigma_statistical}, {"status", p.status},
                      {"reason", p.reason}, {"note", p.note}});
    names.push_back(p.name);
  }
  nlohmann::json corr = nlohmann::json::array();
  for (Eigen::Index i = 0; i < r.correlation.rows(); ++i) {
    std::vector<double> row;
    for (Eigen::Index j = 0; j < r.correlation.cols(); ++j) row.push_back(r.correlation(i, j));
    corr.push_back(row);
  }
  nlohmann::json optima = nlohmann::json::array();
  for (std::size_t k = 0; k < r.optima.size(); ++k) {
    auto o = tube_params_json(r.optima[k]);
    o["chi2"] = 2.0 * r.optima_cost[k];
    optima.push_back(o);
  }
  // The damping model fitted (issue 19): the Rayleigh fields always, the
  // complex constants' Qm with its sigma beside them when that model was fitted.
  nlohmann::json damping = {{"model", update::damping_name(r.damping_model)},
                            {"rayleigh_alpha", r.damping.alpha},
                            {"rayleigh_beta", r.damping.beta}};
  if (r.damping_model == update::OeDamping::complex_constants) {
    damping["qm"] = r.qm;
    damping["qm_sigma"] = r.qm_sigma;
    damping["qm_inverse"] = r.eta;
  }
  return {{"method", "oe"},
          {"converged", r.ok()},
          {"status", update::to_string(r.status)},
          {"message", r.message},
          {"updated", tube_params_json(r.updated)},
          {"parameters", params},
          {"correlation", {{"names", names}, {"matrix", corr}}},
          {"corr_nu12_d31", r.corr_nu12_d31},
          {"damping", damping},
          {"fit",
           {{"excitation", excitation},
            {"shots", r.shots_used},
            {"band_hz", r.band_hz},
            {"residual_samples", r.residual_samples},
            {"noise_source", r.noise_source},
            {"noise_rms_v", r.noise_rms_v},
            {"residual_rms_v", r.residual_rms_v},
            {"chi2_per_dof", r.chi2_per_dof},
            {"chi2_limit", r.chi2_limit},
            {"lack_of_fit", r.lack_of_fit},
            {"offset_model", r.offset_model},
            {"baseline", baseline_json(r.baseline)},
            {"shot_consistency", shot_consistency_json(r.shot_consistency)},
            {"chain_tolerances",
             {{"r1_rel_sigma", r.r1_rel_sigma},
              {"cp_sigma_f", r.cp_sigma_f},
              {"gain_rel_sigma", r.gain_rel_sigma},
              {"skew_sigma_s", r.skew_sigma_s}}},
            {"band_test",
             {{"log10_p", r.band_log10_p},
              {"excess", r.band_excess},
              {"lo_hz", r.band_lo_hz},
              {"hi_hz", r.band_hi_hz},
              {"windows", r.band_windows}}},
            {"noise_dof", r.noise_dof},
            {"starts", r.starts},
            {"iterations", r.iterations},
            {"evaluations", r.evaluations},
            {"optima", optima}}},
          {"effects",
           [&] {
             nlohmann::json a = nlohmann::json::array();
             for (const auto& e : r.effects) {
               a.push_back({{"name", e.name},
                            {"unit", e.unit},
                            {"value", std::isfinite(e.value) ? nlohmann::json(e.value) : nlohmann::json(nullptr)},
                            {"sigma", std::isfinite(e.sigma) ? nlohmann::json(e.sigma) : nlohmann::json(nullptr)},
                            {"delta_chi2", e.delta_chi2},
                            {"alias", e.alias},
                            {"alias_residual", e.alias_residual},
                            {"significant", e.significant},
                            {"explains", e.explains},
                            {"chi2_per_dof", e.chi2_per_dof},
                            {"band_log10_p", e.band_log10_p},
                            {"converged", e.converged},
                            {"updated", tube_params_json(e.material)}});
               if (!e.law.empty()) a.back()["law"] = e.law;
             }
             return a;
           }()},
          {"seconds", r.seconds}};
}

}  // namespace piezo::jobs
