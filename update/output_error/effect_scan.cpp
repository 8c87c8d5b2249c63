// The catalogue's effects scanned beside the output-error fit's five
// coordinates (effect_scan.hpp): the first-order answer or an LM run per
// effect, both dielectric-loss laws, extra starts for an end mass, and the
// regrid of the most significant ones under a lack of fit.
#include "update/output_error/effect_scan.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "model/effects.hpp"
#include "update/output_error/lack_of_fit.hpp"
#include "update/output_error/parallel.hpp"

namespace piezo::update::oe {

namespace {

// An effect's LM run and how it enters (its coordinate, with the law chosen).
struct Refit {
  std::size_t index;  // in out.effects
  std::function<void(model::EffectSet&, double)> apply;
  const model::EffectInfo* info;
  LmOutcome run;
};

// What the scan reads of the fit: its answer, coordinates and options, and
// the result so far (χ²/ν and its limit, the answer's constants, loss and
// covariance, the band test, the lack of fit).
struct ScanInputs {
  const FitAnswer& answer;
  const Coordinates5& co;
  const TubeParams& nominal;
  const OeOptions& opt;
  const OeResult& out;
};

// The effect's numbers from its run.
void fill(const ScanInputs& in, Problem& p, Fitter& f, OeEffect& e, Refit& rf) {
  const LmOutcome& best = in.answer.best;
  const auto& t_best = in.answer.t;
  const double dof = in.answer.dof, ch1 = in.answer.ch1, ch2 = in.answer.ch2;
  const Coordinates5& co = in.co;
  const TubeParams& nominal = in.nominal;
  const OeOptions& opt = in.opt;
  const OeResult& out = in.out;
  LmOutcome& run = rf.run;
  f.finish(run);
  // One Gauss-Newton step on J at the answer (a run with the material
  // columns frozen stops where J₀ᵀr = 0, a fraction of a sigma from Jᵀr = 0).
  if (run.jtj.rows() == run.x.size() && run.r.size() == run.j.rows()) {
    const Eigen::VectorXd step = -run.jtj.ldlt().solve(run.j.transpose() * run.r);
    if (step.allFinite() && step.cwiseAbs().maxCoeff() < 0.3) {
      const Eigen::VectorXd xt = run.x + step;
      if (const auto rt = f.weighted(xt); rt && 0.5 * rt->squaredNorm() < run.cost) {
        run.x = xt;
        run.r = *rt;
        run.cost = 0.5 * rt->squaredNorm();
      }
    }
  }
  e.converged = run.converged;
  e.material = co.params(run.x.head(kParams));
  e.beta_s = co.beta(run.x.head(kParams));
  e.eta = co.eta(run.x.head(kParams));
  e.damping_model = opt.damping;
  e.effect_set = p.effects();
  rf.apply(e.effect_set, run.x[kParams]);
  const double dof_e = std::max(1.0, dof - 1.0);
  e.chi2_per_dof = 2.0 * run.cost / dof_e;
  e.delta_chi2 = 2.0 * (best.cost - run.cost);
  double sx = NAN;  // the coordinate's σ
  if (run.jtj.rows() == kParams + 1) {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(run.jtj);
    if (lu.isInvertible()) {
      const Eigen::MatrixXd ce = std::max(1.0, e.chi2_per_dof) * lu.inverse();
      sx = std::sqrt(std::max(0.0, ce(kParams, kParams)));
      e.covariance_rel = ce;
      const double k = nominal.nu12 / e.material.nu12;
      e.covariance_rel.row(1) *= k;
      e.covariance_rel.col(1) *= k;
    }
  }
  // From the coordinate (a conductance's σ_R = σ_G/G²).
  e.value = model::effect_from_coordinate(*rf.info, run.x[kParams]);
  e.sigma = model::effect_sigma_from_coordinate(*rf.info, run.x[kParams], sx);
  const auto st = spectral_lack_of_fit(run.r, p.residual_psd(*t_best, ch1, ch2), p.residual_bin_hz());
  e.band_log10_p = st.log10_p;
  const bool physical = model::effect_value_physical(*rf.info, e.value);
  e.significant = !e.alias && run.converged && physical &&
                  e.delta_chi2 > opt.effect_significance * std::max(1.0, e.chi2_per_dof);
  e.explains = e.significant && e.chi2_per_dof <= out.chi2_limit && st.log10_p >= std::log10(opt.lack_of_fit_p);
}

struct Scanned {
  OeEffect e;
  std::optional<Refit> rf;  // an LM run (not the linear answer)
};

// The effect at the optimum to first order: x0 is the optimum with the
// effect at 0. Sets e's alias numbers (alias_residual, bias_pct,
// detectability, alias).
struct FirstOrder {
  double score = INFINITY, step_lin = 0, jperp2 = 0;
  Eigen::MatrixXd j_start;  // J at x0: the five's columns at the optimum and the effect's
};
FirstOrder first_order(const ScanInputs& in, Fitter& f, const Eigen::VectorXd& x0, OeEffect& e) {
  const LmOutcome& best = in.answer.best;
  const OeOptions& opt = in.opt;
  FirstOrder fo;
  double& score = fo.score;
  double& step_lin = fo.step_lin;
  double& jperp2 = fo.jperp2;
  Eigen::MatrixXd& j_start = fo.j_start;
  // Alias: the effect's column against the five's at their optimum. And
  // the score test there (Rao): the χ² drop the effect would bring to first
  // order, (j⊥ᵀr)²/‖j⊥‖², j⊥ its column beyond the five's span.
  if (auto r0 = f.weighted(x0)) {
    Eigen::VectorXd xp = x0;
    xp[kParams] = 1e-4;
    if (auto rp = f.weighted(xp)) {
      const Eigen::VectorXd je = (*rp - *r0) / 1e-4;
      if (best.j.rows() == je.size()) {
        j_start.resize(je.size(), kParams + 1);
        j_start << best.j, je;
      }
      const Eigen::VectorXd c = best.j.colPivHouseholderQr().solve(je);
      const Eigen::VectorXd jperp = je - best.j * c;
      e.alias_residual = je.norm() > 0 ? jperp.norm() / je.norm() : 0.0;
      // x₆ = 1 is `typical`; the constants' coordinates are logs (nu12 relative).
      for (int i = 0; i < 4; ++i) e.bias_pct[i] = 100.0 * c[i];
      jperp2 = jperp.squaredNorm();
      e.detectability = std::sqrt(jperp2);
      if (jperp2 > 0) {
        const double g = jperp.dot(*r0);
        score = g * g / jperp2;
        step_lin = -g / jperp2;
      }
    }
  }
  e.alias = e.alias_residual < opt.alias_threshold;
  return fo;
}

// One effect of the catalogue (effect_coordinate(name) exists) from the
// optimum, on Problem p with its fitter f.
Scanned scan_one(const ScanInputs& in, Problem& p, Fitter& f, const std::string& name) {
  const LmOutcome& best = in.answer.best;
  const double dof = in.answer.dof;
  const OeOptions& opt = in.opt;
  const OeResult& out = in.out;
  Scanned s;
  const model::EffectInfo* info = model::find_effect(name);
  const auto coord = effect_coordinate(name);
  const auto& apply = coord->apply;
  OeEffect e;
  const int models_before = p.evaluations();
  e.name = name;
  e.typical = info->typical;
  e.unit = info->unit;
  p.free_effect(apply);
  Eigen::VectorXd x0(kParams + 1);
  x0 << best.x, 0.0;
  const FirstOrder fo = first_order(in, f, x0, e);
  const double score = fo.score, step_lin = fo.step_lin, jperp2 = fo.jperp2;
  const Eigen::MatrixXd& j_start = fo.j_start;
  // Far below significance to first order (and not the end mass, whose
  // effect grows faster than linearly): the linear answer, no refit.
  if (!e.alias && !info->moves_modes && score < opt.effect_significance / 4 && jperp2 > 0) {
    const double s2e = std::max(1.0, out.chi2_per_dof);
    e.converged = true;
    e.linearised = true;
    e.material = out.updated;
    e.beta_s = out.damping.beta;
    e.eta = out.eta;
    e.damping_model = out.damping_model;
    e.effect_set = p.effects();
    apply(e.effect_set, step_lin);
    e.delta_chi2 = score;
    e.chi2_per_dof = (2.0 * best.cost - score) / std::max(1.0, dof - 1.0);
    e.value = model::effect_from_coordinate(*info, step_lin);
    e.sigma = model::effect_sigma_from_coordinate(*info, step_lin, std::sqrt(s2e / jperp2));
    e.band_log10_p = out.band_log10_p;
    e.covariance_rel = Eigen::MatrixXd::Zero(kParams + 1, kParams + 1);
    e.covariance_rel.topLeftCorner(kParams, kParams) = out.covariance_rel;
    e.covariance_rel(kParams, kParams) = s2e / jperp2;
    s.e = std::move(e);
    return s;
  }
  // An end mass moves the modes far along a curved valley the five already
  // follow part way (4 % of added mass fits as YE11 −2.8 % at χ²/ν ≈ 1):
  // from the optimum alone LM stays at none, so where the capture shows a
  // misfit it also starts at 2 % and 4 % (each evaluation an FE model).
  const Eigen::MatrixXd* j0 = j_start.size() ? &j_start : nullptr;
  // (The end mass moves the modes themselves: its runs keep the exact J.)
  LmOutcome run = f.levenberg_marquardt(x0, nullptr, j0, !info->moves_modes);
  if (!run.converged && !info->moves_modes && std::isfinite(run.cost)) {
    // The frozen columns did not get there: on from where it stopped, exactly.
    LmOutcome exact = f.levenberg_marquardt(run.x, nullptr);
    if (exact.converged || exact.cost < run.cost) run = std::move(exact);
  }
  if (info->moves_modes && out.lack_of_fit) {
    // The later starts stop once inside the best one's optimum or stalled
    // far above it (levenberg_marquardt's lead test, on the six).
    f.finish(run);
    for (double start : {2.0, 4.0}) {  // 2 and 4 typical sizes (2 % and 4 % of the tube's mass)
      Eigen::VectorXd xs = x0;
      xs[kParams] = start;
      LmOutcome other = f.levenberg_marquardt(xs, &run);
      if (other.cost < run.cost) {
        run = std::move(other);
        f.finish(run);
      }
    }
  }
  // Dielectric loss: the FE convention (a constant complex εT33) and the
  // causal constant-phase law differ by ε' falling ~1.5·tanδ per decade —
  // at 1 % noise a misfit of its own; the capture chooses.
  if (name == "dielectric_loss") {
    e.law = "frequency-independent";
    p.free_effect([apply](model::EffectSet& fx, double x) {
      apply(fx, x);
      fx.dielectric_constant_phase = true;
    });
    LmOutcome causal = f.levenberg_marquardt(x0, nullptr);  // (its effect column is another)
    if (causal.cost < run.cost) {
      run = std::move(causal);
      e.law = "constant-phase";
    } else {
      p.free_effect(apply);
    }
  }
  Refit rf{0, apply, info, std::move(run)};
  // The runs above went on the surrogate (Problem::set_surrogate): the one
  // kept is evaluated on exact models where it ended, and fill() gives it a
  // Gauss–Newton step on the exact Jacobian there.
  const bool surrogate = p.surrogate();
  if (surrogate) {
    p.set_surrogate(false);
    if (const auto r = f.weighted(rf.run.x)) {
      rf.run.r = *r;
      rf.run.cost = 0.5 * r->squaredNorm();
    } else {  // (the exact model cannot be built there: the run from the optimum, exactly)
      rf.run = f.levenberg_marquardt(x0, nullptr);
    }
  }
  if (e.law == "constant-phase")
    rf.apply = [apply](model::EffectSet& fx, double x) {
      apply(fx, x);
      fx.dielectric_constant_phase = true;
    };
  fill(in, p, f, e, rf);
  e.port_tangent = p.export_tangent();
  if (surrogate) p.set_surrogate(true);
  e.fe_models = p.evaluations() - models_before;
  s.e = std::move(e);
  s.rf = std::move(rf);
  return s;
}

// Under a lack of fit the five may sit in another basin (β and a shifted
// YE11/nu12 absorbing part of the effect: a 30 Ω lead on one 2 % shot fits
// as YE11 −3.5 %, nu12 −12 %, β ×1.8); from there the sixth coordinate
// cannot leave it. The two most significant effects get the coarse grid
// again, at their fitted value, and LM from the grid's best point. Returns
// the FE models the fork built.
int regrid_effects(const ScanInputs& in, Fitter& fitter, std::vector<Refit>& refits,
                   OeResult& out) {
  const OeOptions& opt = in.opt;
  Problem& prob = fitter.prob;
  std::vector<Refit*> order;
  for (auto& rf : refits)
    if (out.effects[rf.index].delta_chi2 > opt.effect_significance) order.push_back(&rf);
  std::sort(order.begin(), order.end(), [&](const Refit* a, const Refit* b) {
    return out.effects[a->index].delta_chi2 > out.effects[b->index].delta_chi2;
  });
  if (order.size() > 2) order.resize(2);
  // Each from the state after the scan, side by side (in_parallel).
  std::vector<std::size_t> tasks(order.size());
  for (std::size_t k = 0; k < tasks.size(); ++k) tasks[k] = k;
  return in_parallel(fitter, tasks, prob.state(), [&](Problem& p, Fitter& f, std::size_t k) {
    Refit* rf = order[k];
    p.free_effect(rf->apply);
    const int models_before = p.evaluations();
    Eigen::VectorXd xg_best;
    double cg_best = INFINITY;
    std::vector<Eigen::VectorXd> regrid;
    std::vector<std::pair<Eigen::VectorXd, double>> points;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b) {
        Eigen::VectorXd xg = Eigen::VectorXd::Zero(kParams + 1);
        xg[0] = std::log1p(a * opt.grid_span_ye11);
        xg[1] = b * opt.grid_span_nu12;
        xg[4] = rf->run.x[4];
        xg[kParams] = rf->run.x[kParams];
        regrid.push_back(xg);
        points.emplace_back(xg, p.effects_at(xg).mass_loading);
      }
    p.prefetch(points);
    for (const auto& xg : regrid) {
      const auto rg = f.weighted(xg);
      const double cg = rg ? 0.5 * rg->squaredNorm() : INFINITY;
      if (cg < cg_best) cg_best = cg, xg_best = xg;
    }
    if (!std::isfinite(cg_best)) return;
    // (fill() has finished the run: it leads, as the first start leads the five's later ones.)
    LmOutcome other = f.levenberg_marquardt(xg_best, &rf->run);
    if (other.cost < rf->run.cost) {
      rf->run = std::move(other);
      fill(in, p, f, out.effects[rf->index], *rf);  // (each task its own effect)
      out.effects[rf->index].port_tangent = p.export_tangent();
    }
    out.effects[rf->index].fe_models += p.evaluations() - models_before;
  });
}

}  // namespace

int scan_effects(const FitAnswer& answer, Fitter& fitter, const Coordinates5& co,
                 const TubeParams& nominal, const OeOptions& opt, OeResult& out) {
  const ScanInputs in{answer, co, nominal, opt, out};
  const LmOutcome& best = answer.best;
  const auto& t_best = answer.t;
  Problem& prob = fitter.prob;
  int models_elsewhere = 0;
  std::vector<Refit> refits;
  // The catalogue's effects, one at a time, as a sixth coordinate from the
  // optimum (effect_coordinate). Each starts from the optimum's state
  // (Problem::State) and runs on one of up to two threads — the fit's solver
  // and a second one, each with its own Problem — so its answer is the same
  // whatever thread runs it and in what order; the result lists them in the
  // catalogue's order.
  std::vector<std::string> scan_names;
  if (best.converged && best.j.rows() != 0 && t_best)
    for (const auto& name : opt.scan_effects) {
      if (!model::find_effect(name))
        throw std::invalid_argument("scan_effects: no effect '" + name + "' in the catalogue");
      if (effect_coordinate(name)) scan_names.push_back(name);  // (else in the catalogue, not in this model)
    }
  // The scan's runs on the surrogate (Problem::set_surrogate: port models
  // from reduced bases about the optimum and along each run), each then
  // polished on exact models (scan_one); the forks below share the
  // optimum's basis.
  if (!scan_names.empty() && opt.scan_surrogate) {
    prob.use_reduced(best.x, prob.effects().mass_loading);
    prob.set_surrogate(true);
  }
  {
    std::vector<Scanned> scanned(scan_names.size());
    // The longest first: an end mass (up to three LM runs, an FE model per
    // evaluation), the dielectric loss (two laws).
    auto rank = [](const std::string& n) {
      return model::find_effect(n)->moves_modes ? 0 : n == "dielectric_loss" ? 1 : 2;
    };
    std::vector<std::size_t> order(scan_names.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return rank(scan_names[a]) < rank(scan_names[b]); });
    models_elsewhere += in_parallel(fitter, order, prob.state(), [&](Problem& p, Fitter& f, std::size_t i) {
      scanned[i] = scan_one(in, p, f, scan_names[i]);
    });
    for (auto& s : scanned) {
      if (s.rf) {
        s.rf->index = out.effects.size();
        refits.push_back(std::move(*s.rf));
      }
      out.effects.push_back(std::move(s.e));
    }
  }
  prob.drop_reduced();
  if (out.lack_of_fit) models_elsewhere += regrid_effects(in, fitter, refits, out);
  prob.free_effect({});
  std::sort(out.effects.begin(), out.effects.end(),
            [](const OeEffect& a, const OeEffect& b) { return a.delta_chi2 > b.delta_chi2; });
  return models_elsewhere;
}

}  // namespace piezo::update::oe
