#include "dsp/uncertain_text.hpp"
#include "update/gap_diagnosis.hpp"
#include "update/gap_core.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>

#include "model/bench_response.hpp"
#include "model/effects.hpp"

namespace piezo::update {

namespace {
using cd = std::complex<double>;
constexpr int kBase = 6;  // material (4) + damping (2)

double excess_gap(double chi2, int n) { return gap_core::excess(chi2 / std::max(1, n)); }

// A gap is a misfit beyond 3σ of χ²'s spread AND beyond `tolerance` of the
// noise variance: the noise itself is measured from the shots (≈ 16 shots ×
// 9 smoothed bins), so χ²/N of an exact model scatters by ~10-20 % around 1
// (tests/update/test_gap_diagnosis.cpp measures it).
bool significant_gap(double chi2, int dof, double tolerance) {
  const double n = std::max(1, dof);
  return chi2 > n + std::max(3.0 * std::sqrt(2.0 * n), tolerance * n);
}

GapCurve curve_of(const GapModel& m, const GapData& d, const std::vector<double>& x) {
  GapCurve c;
  const auto z = m.impedance(x, d.f_hz);
  const double db = 20.0 / std::log(10.0), deg = 180.0 / M_PI;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const cd l = std::log(d.z_ohm[i] / z[i]);
    c.f_hz.push_back(d.f_hz[i]);
    c.residual_db.push_back(db * l.real());
    c.residual_deg.push_back(deg * l.imag());
    c.sigma_db.push_back(db * d.sigma_log_mag[i]);
    c.sigma_deg.push_back(deg * d.sigma_phase[i]);
    c.measured_abs_ohm.push_back(std::abs(d.z_ohm[i]));
  }
  return c;
}

// x's material coordinates for the material p (GapModel: 1 % per unit from
// `ref`); false when p cannot be expressed (a sign change, say).
bool material_coords(const TubeParams& p, const TubeParams& ref, std::vector<double>& x) {
  const double v[4] = {std::log(p.y_e11 / ref.y_e11) / 0.01, std::log(p.nu12 / ref.nu12) / 0.01,
                       std::log(p.d31 / ref.d31) / 0.01, std::log(p.eps_t33 / ref.eps_t33) / 0.01};
  for (int i = 0; i < 4; ++i) {
    if (!std::isfinite(v[i])) return false;
    x[static_cast<std::size_t>(i)] = v[i];
  }
  return true;
}

std::vector<double> extend(const std::vector<double>& base, const GapModel& m) {
  std::vector<double> x = m.reference_x();
  for (std::size_t i = 0; i < base.size() && i < x.size(); ++i) x[i] = base[i];
  return x;
}
// The misfit of `d` at x as a residual spectrum (update/residual_regions.hpp)
// in impedance terms: "T" is the reported Z of the model, the drive 1,
// e = Z_model − Z_meas, var = |Z|²(σ_ln|Z|² + σ_phase²), ∂Z/∂Y of the
// transducer's admittance through the bench's effects — so that an extra
// resonance, a level, a phase or a phase slope read the same as in the
// output-error diagnosis (issue 21). Empty when the model cannot be built.
std::vector<ResidualRegion> located_regions(const GapModel& m, const GapData& d, const std::vector<double>& x,
                                            double r1_nominal_ohm) {
  model::ModalPortModel port;
  try {
    port = m.exact_port(x);
  } catch (const std::exception&) {
    return {};
  }
  const auto damp = m.damping(x);
  const auto fx = m.effects(x);
  ResidualSpectrum s;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double w = 2.0 * M_PI * d.f_hz[i];
    if (!(w > 0)) continue;
    const std::complex<double> y = model::tube_admittance(port, damp, fx, w);
    const std::complex<double> z = model::reported_impedance(y, fx, r1_nominal_ohm, w);
    const std::complex<double> dy = 1e-6 * std::abs(y);
    const std::complex<double> dz = (model::reported_impedance(y + dy, fx, r1_nominal_ohm, w) - z) / dy;
    const double var = std::norm(d.z_ohm[i]) * (d.sigma_log_mag[i] * d.sigma_log_mag[i] + d.sigma_phase[i] * d.sigma_phase[i]);
    if (!(var > 0) || !std::isfinite(var) || !std::isfinite(std::abs(z))) continue;
    s.f_hz.push_back(d.f_hz[i]);
    s.e.push_back(z - d.z_ohm[i]);
    s.lv1.push_back(1.0);
    s.t.push_back(z);
    s.dt_dy.push_back(dz);
    s.y_tube.push_back(y);
    s.var.push_back(var);
  }
  return residual_regions(s, 2, 1e-3);
}

}  // namespace

std::vector<std::string> supported_gap_effects() {
  std::vector<std::string> out;
  for (const auto& e : model::effect_catalogue())
    out.emplace_back(e.name);
  return out;
}

GapDiagnosis diagnose_gap(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& start,
                          const model::RayleighDamping& damping_start, double r1, const GapData& fit,
                          const GapData* heldout, const GapOptions& opt,
                          const std::function<void(double, const std::string&)>& progress,
                          const std::atomic<bool>* cancel) {
  const auto t0 = std::chrono::steady_clock::now();
  fit.validate("diagnose_gap (fit data)");
  if (heldout) heldout->validate("diagnose_gap (held-out data)");
  auto say = [&](double f, const std::string& s) {
    if (progress) progress(f, s);
  };
  auto cancelled = [&] { return cancel && cancel->load(); };
  std::vector<std::string> candidates = opt.candidates.empty() ? supported_gap_effects() : opt.candidates;
  model::EffectSet fixed;
  for (const auto& me : opt.measured) {
    const auto* info = model::find_effect(me.name);
    if (!info) throw std::invalid_argument("gap diagnosis: unknown measured effect '" + me.name + "'");
    if (!std::isfinite(me.value) || me.value < info->lower || me.value > info->upper)
      throw std::invalid_argument("gap diagnosis: measured " + me.name + " = " + std::to_string(me.value) +
                                  " lies outside its physical bounds");
    fixed.*(info->field) = me.value;
    std::erase(candidates, me.name);  // known: neither a candidate nor an alias
  }

  GapDiagnosis out;
  out.fit_description = fit.description;
  if (heldout) out.heldout_description = heldout->description;
  out.measured = opt.measured;
  // The update's constants can sit at the edge of the physical domain (an
  // output-error fit that compensated a strong unmodelled loss with a coupling
  // near 1): the linearisation steps around them cross it. Then the model is
  // linearised at the first other start (the nominal material) instead.
  std::unique_ptr<GapModel> mp;
  try {
    mp = std::make_unique<GapModel>(solver, cls, start, damping_start, r1, opt.damping_ref_hz);
  } catch (const std::invalid_argument&) {
    if (opt.other_starts.empty()) throw;
    mp = std::make_unique<GapModel>(solver, cls, opt.other_starts.front(), damping_start, r1, opt.damping_ref_hz);
    out.base_from_other_start = true;
  }
  GapModel& m = *mp;
  m.set_fixed_effects(fixed);

  // 1. Base fit: material + damping.
  say(0.0, "gap: refitting material and damping to the whole curve");
  std::vector<bool> free_base(kBase, true);
  GapFit base = fit_gap(m, fit, m.reference_x(), free_base, opt.fit);
  if (!base.converged) throw std::runtime_error("gap diagnosis: " + base.message);
  if (significant_gap(base.chi2, base.dof, opt.gap_tolerance) && !opt.other_starts.empty()) {
    const std::vector<double> lin_base = base.x;  // where m is linearised now
    bool moved = false;
    for (const auto& p : opt.other_starts) {
      if (cancelled()) return out;
      say(0.02, "gap: refitting from another start (the updated constants leave a gap)");
      std::vector<double> x = m.reference_x();
      if (!material_coords(p, start, x)) continue;
      try {
        m.relinearise(x);
        GapFit alt = fit_gap(m, fit, x, free_base, opt.fit);
        if (alt.converged && alt.chi2 < base.chi2) {
          base = alt;
          moved = true;
          out.base_from_other_start = true;
        } else {
          m.relinearise(base.x);
        }
      } catch (const std::exception&) {
        m.relinearise(base.x);  // a start the FE cannot solve: keep the first fit
      }
    }
    if (!moved) m.relinearise(lin_base);
  }
  out.material_base = m.material(base.x);
  out.damping_base = m.damping(base.x);
  out.chi2_fit = base.chi2;
  out.n_fit = base.n;
  out.dof_fit = base.dof;
  out.gap_fit = std::sqrt(base.chi2 / std::max(1, base.dof));
  if (heldout) {
    out.chi2_heldout = predictive_chi2(m, *heldout, base);
    out.n_heldout = static_cast<int>(2 * heldout->size());
    out.gap_heldout = std::sqrt(*out.chi2_heldout / out.n_heldout);
  }
  out.gap = significant_gap(base.chi2, base.dof, opt.gap_tolerance) ||
            (heldout && significant_gap(*out.chi2_heldout, out.n_heldout, opt.gap_tolerance));
  out.regions = gap_regions(m, fit, base.x);
  out.before = curve_of(m, fit, base.x);

  // 2. Identifiability of every candidate at the base point, then its refit.
  std::vector<std::string> model_effects;  // added so far (greedy)
  std::vector<double> x_cur = base.x;
  double chi_cur = base.chi2;
  std::optional<double> ho_cur = out.chi2_heldout;
  std::vector<std::string> pool = candidates;
  std::map<std::string, Eigen::VectorXd> signature;  // first round: (I − P)·j of each candidate
  for (int round = 0; round < std::max(1, opt.max_effects); ++round) {
    std::vector<EffectReport> reports;
    for (std::size_t c = 0; c < pool.size(); ++c) {
      if (cancelled()) return out;
      say(0.1 + 0.85 * (round * pool.size() + c) / double(std::max<std::size_t>(1, opt.max_effects * pool.size())),
          "gap: trying " + pool[c]);
      EffectReport rep;
      rep.name = pool[c];
      const auto* info = model::find_effect(pool[c]);
      if (!info) throw std::invalid_argument("gap diagnosis: unknown effect '" + pool[c] + "'");
      rep.unit = std::string(info->unit);
      rep.typical = info->typical;  // in the effect's unit (the catalogue's; x = 1 is this size)
      const double x_unit = model::effect_coordinate_unit(*info);  // the coordinate's unit (S for the DAQ's input)
      std::vector<std::string> fx = model_effects;
      fx.push_back(pool[c]);
      m.set_effects(fx);
      std::vector<double> x0 = extend(x_cur, m);
      const int je = m.size() - 1;
      // Alias test: the new column against the span of all the others.
      std::vector<int> others;
      for (int j = 0; j < je; ++j) others.push_back(j);
      const auto jo = gap_jacobian(m, fit, x0, others);
      const auto jn = gap_jacobian(m, fit, x0, {je}).front();
      const int nr = static_cast<int>(jn.size());
      Eigen::MatrixXd a(nr, je);
      for (int j = 0; j < je; ++j) a.col(j) = Eigen::Map<const Eigen::VectorXd>(jo[static_cast<std::size_t>(j)].data(), nr);
      const Eigen::VectorXd v = Eigen::Map<const Eigen::VectorXd>(jn.data(), nr);
      const Eigen::VectorXd coef = a.completeOrthogonalDecomposition().solve(v);
      const Eigen::VectorXd rest = v - a * coef;
      rep.alias_residual = v.norm() > 0 ? rest.norm() / v.norm() : 0.0;
      rep.detectability = rest.norm();
      if (round == 0) signature[pool[c]] = rest;
      // A typical magnitude of the effect, fitted with the constants only,
      // moves them by −coef (x units are % for the material).
      rep.bias_y_e11_pct = -coef(0);
      rep.bias_nu12_pct = -coef(1);
      rep.bias_d31_pct = -coef(2);
      rep.bias_eps_t33_pct = -coef(3);
      rep.alias = rep.alias_residual < opt.alias_threshold;
      if (rep.alias) {
        rep.note = "cannot be told from the material constants by the impedance alone";
        reports.push_back(rep);
        continue;
      }
      std::vector<bool> free(static_cast<std::size_t>(m.size()), true);
      GapFit f = fit_gap(m, fit, x0, free, opt.fit);
      std::string law;
      if (pool[c] == "dielectric_loss") {
        // Both laws in frequency (model/effects.hpp): the FE convention and the
        // causal constant-phase one; the data choose, and the law chosen stays
        // in the model (it acts only where the loss is non-zero).
        model::EffectSet fxd = m.fixed_effects();
        const bool was = fxd.dielectric_constant_phase;
        fxd.dielectric_constant_phase = !was;
        m.set_fixed_effects(fxd);
        GapFit g = fit_gap(m, fit, x0, free, opt.fit);
        if (g.converged && g.chi2 < f.chi2) {
          f = std::move(g);
        } else {
          fxd.dielectric_constant_phase = was;
          m.set_fixed_effects(fxd);
        }
        law = m.fixed_effects().dielectric_constant_phase ? "constant-phase" : "frequency-independent";
      }
      rep.fitted = true;
      rep.value = m.effect_value(f.x, je);
      rep.sigma = f.sigma_x[static_cast<std::size_t>(je)] * x_unit;
      if (info->coordinate == model::EffectCoordinate::conductance) {  // fitted as G; σ_R = σ_G·R²
        rep.sigma = std::isfinite(rep.value) ? rep.sigma * rep.value * rep.value : std::numeric_limits<double>::infinity();
      }
      rep.chi2_after = f.chi2;
      rep.delta_chi2 = chi_cur - f.chi2;
      rep.shrink_fit = 1.0 - excess_gap(f.chi2, f.dof) / std::max(1e-300, excess_gap(chi_cur, f.dof + 1));
      const double scale = std::max(1.0, f.chi2 / std::max(1, f.dof));
      // Significant: the misfit drops beyond the threshold AND the effect's
      // own magnitude stands clear of zero (≥ opt.min_effect_sigma of its
      // uncertainty). A refit that lowers χ² with the effect at its neutral
      // value has only moved the constants to a better optimum (a base fit
      // left in a poor basin by a failed update): no evidence for the effect.
      const double xe = f.x[static_cast<std::size_t>(je)] - x0[static_cast<std::size_t>(je)];
      const double sx = f.sigma_x[static_cast<std::size_t>(je)];
      const bool stands_clear = sx > 0 ? std::fabs(xe) / sx >= opt.min_effect_sigma : xe != 0.0;
      rep.significant = rep.delta_chi2 / scale > opt.significance && stands_clear;
      rep.material = m.material(f.x);
      for (std::size_t i = 0; i < 4 && i < f.sigma_x.size(); ++i)  // x: 1 % per unit (gap_model.hpp)
        rep.material_rel_sigma[i] = f.converged && f.sigma_x[i] > 0 ? 0.01 * f.sigma_x[i] : NAN;
      if (!f.converged) rep.note = f.message;
      else if (!law.empty()) rep.note = "law in frequency: " + law + " (the better fit of the two)";
      else if (!info->note.empty())
        rep.note = info->note;
      if (heldout) {
        rep.heldout_chi2_after = predictive_chi2(m, *heldout, f);
        const double n = std::max(1, out.n_heldout);
        rep.heldout_shrink = gap_core::shrink(*ho_cur / n, *rep.heldout_chi2_after / n).value_or(0.0);
      }
      reports.push_back(rep);
    }
    // Rank: identifiable and fitted first, by held-out χ² (or fit χ²), aliases last.
    std::stable_sort(reports.begin(), reports.end(), [&](const EffectReport& p, const EffectReport& q) {
      if (p.alias != q.alias) return !p.alias;
      if (p.alias) return p.alias_residual < q.alias_residual;
      if (p.heldout_chi2_after && q.heldout_chi2_after) return *p.heldout_chi2_after < *q.heldout_chi2_after;
      return p.chi2_after < q.chi2_after;
    });
    if (round == 0) {
      // Pairs of identifiable candidates the data cannot tell apart.
      for (auto& r : reports) {
        if (r.alias) continue;
        const Eigen::VectorXd& a = signature[r.name];
        for (const auto& q : reports) {
          if (q.alias || q.name == r.name) continue;
          const Eigen::VectorXd& b = signature[q.name];
          const double den = a.norm() * b.norm();
          if (den > 0 && std::abs(a.dot(b)) / den >= opt.indistinguishable_cos) r.indistinguishable_from.push_back(q.name);
        }
      }
      out.effects = reports;
    }
    // Greedy step: the round's best identifiable effect, if it is significant
    // on the fit data and passes the core's held-out check (gap_core.hpp):
    // where the held-out data show a gap, it must shrink it; where they show
    // none (a less sensitive drive or noisier capture: the model already
    // predicts them within their noise), there is nothing to shrink, and the
    // effect must not make them worse (its held-out χ² may not rise by more
    // than the significance threshold or 3σ of χ²).
    const EffectReport* best = nullptr;
    for (const auto& r : reports)
      if (!r.alias && r.fitted) {
        best = &r;
        break;
      }
    const bool gap_left = significant_gap(chi_cur, out.dof_fit - static_cast<int>(model_effects.size()), opt.gap_tolerance) ||
                          (ho_cur && significant_gap(*ho_cur, out.n_heldout, opt.gap_tolerance));
    std::vector<gap_core::CandidateEvidence> offered;  // the best, if significant (explains: no lack-of-fit test here)
    if (best && best->significant) {
      gap_core::CandidateEvidence c{best->name, true, true};
      if (ho_cur && best->heldout_chi2_after) {
        c.heldout_predicted = true;
        c.heldout_shrink = best->heldout_shrink.value_or(0.0);
        c.heldout_within_noise = *best->heldout_chi2_after <=
                                 *ho_cur + std::max(opt.significance, 3.0 * std::sqrt(2.0 * out.n_heldout));
      }
      offered.push_back(std::move(c));
    }
    gap_core::ChoiceRule rule;
    rule.heldout = ho_cur.has_value();
    rule.heldout_gap = ho_cur && significant_gap(*ho_cur, out.n_heldout, opt.gap_tolerance);
    rule.min_shrink = opt.min_heldout_shrink;
    rule.dominant_shrink = opt.min_heldout_shrink;  // every offered candidate is significant and explains
    rule.first_only = true;
    if (!gap_left || !gap_core::choose_effect(offered, rule).chosen) break;
    if (ho_cur && !significant_gap(*ho_cur, out.n_heldout, opt.gap_tolerance) && out.steps.empty())
      out.heldout_without_gap = true;
    out.steps.push_back(*best);
    model_effects.push_back(best->name);
    // Refit the model with the added effect to carry on from its optimum.
    m.set_effects(model_effects);
    std::vector<bool> free(static_cast<std::size_t>(m.size()), true);
    GapFit f = fit_gap(m, fit, extend(x_cur, m), free, opt.fit);
    x_cur = f.x;
    chi_cur = f.chi2;
    if (heldout) ho_cur = predictive_chi2(m, *heldout, f);
    pool.erase(std::find(pool.begin(), pool.end(), best->name));
    // Aliases stay aliases; only identifiable effects go on.
    std::vector<std::string> keep;
    for (const auto& r : reports)
      if (!r.alias && r.name != best->name) keep.push_back(r.name);
    pool = keep;
    if (pool.empty()) break;
  }
  out.added = model_effects;
  m.set_effects(model_effects);
  out.after = curve_of(m, fit, x_cur);
  if (heldout && !model_effects.empty() && out.chi2_heldout && !out.heldout_without_gap) {
    const double before = excess_gap(*out.chi2_heldout, out.n_heldout);
    out.heldout_shrink = before > 0 ? 1.0 - excess_gap(*ho_cur, out.n_heldout) / before : 0.0;
  }

  // 3. Verdict.
  std::string alias_note = gap_core::alias_sentence(gap_core::alias_names(out.effects), "the impedance alone");
  if (!out.measured.empty()) {
    alias_note += " Measured by the fixture calibration and held in the model: ";
    for (std::size_t i = 0; i < out.measured.size(); ++i) {  // with its unit (the effect table's, SI-prefixed)
      const auto* info = model::find_effect(out.measured[i].name);
      const std::string unit = info ? std::string(info->unit) : std::string();
      alias_note += std::string(i ? ", " : "") + out.measured[i].name + " " +
                    dsp::format_value(out.measured[i].value, unit, 4);
    }
    alias_note += ".";
  }
  if (out.base_from_other_start)
    alias_note += " The constants were refitted from the nominal material: the updated ones left a gap that "
                  "another start removes, or sat at the edge of the physical domain (the update had not found "
                  "them; see its stage note).";
  char buf[512];
  if (!out.gap) {
    out.verdict_effect = "none";
    std::snprintf(buf, sizeof buf, "No gap: the updated model matches the measurement within its noise (chi2/dof %.2f%s).",
                  out.gap_fit, out.gap_heldout ? (", held-out " + std::to_string(*out.gap_heldout).substr(0, 4)).c_str() : "");
    out.verdict = buf + alias_note;
  } else if (!out.added.empty()) {
    const auto& s = out.steps.front();
    out.verdict_effect = s.name;
    std::string more;
    for (std::size_t i = 1; i < out.added.size(); ++i) more += (i == 1 ? "; then " : ", ") + out.added[i];
    if (out.heldout_without_gap)
      std::snprintf(buf, sizeof buf,
                    "Gap explained by %s = %s (fit gap shrinks by %.0f %%; the held-out data show no gap "
                    "to shrink, chi2/dof %.2f, and stay within their noise with it)%s.",
                    s.name.c_str(), dsp::format_uncertain(s.value, s.sigma, s.unit).c_str(), 100 * s.shrink_fit,
                    out.gap_heldout.value_or(0.0), more.c_str());
    else
      std::snprintf(buf, sizeof buf, "Gap explained by %s = %s (held-out gap shrinks by %.0f %%)%s.",
                    s.name.c_str(), dsp::format_uncertain(s.value, s.sigma, s.unit).c_str(),
                    100 * (out.heldout_shrink ? *out.heldout_shrink : s.shrink_fit), more.c_str());
    for (const auto& e : out.effects)
      if (e.name == s.name) out.verdict_alternatives = e.indistinguishable_from;
    out.verdict = buf + gap_core::twins_sentence(out.verdict_alternatives, "This data") + alias_note;
  } else {
    out.verdict_effect = "unexplained";
    const GapRegion* worst = nullptr;
    for (const auto& g : out.regions)
      if (!worst || g.chi2 > worst->chi2) worst = &g;
    const bool fit_gap = significant_gap(out.chi2_fit, out.dof_fit, opt.gap_tolerance);
    // Where the misfit stands above the noise and what it looks like there
    // (issue 21): on the fit data, or on the held-out data when only they
    // show the gap; listed before the engineer's named regions.
    const bool located_heldout = !fit_gap && heldout;
    const auto located = located_regions(m, located_heldout ? *heldout : fit, base.x, r1);
    const std::vector<GapRegion> first = located_gap_regions(located, located_heldout);
    const std::string where = located_sentence(first, located_heldout ? "held-out data" : "misfit");
    if (fit_gap)
      std::snprintf(buf, sizeof buf,
                    "Unexplained gap (chi2/dof %.2f), mostly at %s (%s): no effect of the catalogue explains it on held-out data.",
                    out.gap_fit, worst ? worst->name.c_str() : "?", worst ? worst->kind.c_str() : "?");
    else  // the model fits its own data to the noise but misses the held-out data
      std::snprintf(buf, sizeof buf,
                    "Unexplained gap on the held-out data only (chi2/dof %.2f there, %.2f on the fit data): no effect of "
                    "the catalogue explains it; a second capture would tell a real gap from a held-out capture that "
                    "differs (drive, fixture, temperature).",
                    out.gap_heldout.value_or(0.0), out.gap_fit);
    out.verdict = buf + where + alias_note;
    out.regions.insert(out.regions.begin(), first.begin(), first.end());  // (after `worst` is used)
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  say(1.0, "gap: done");
  return out;
}

}  // namespace piezo::update
