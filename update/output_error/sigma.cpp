// Covariance, sigmas and identifiability of the output-error fit (sigma.hpp).
#include "dsp/probability_text.hpp"
#include "update/output_error/sigma.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <utility>

#include "model/material.hpp"

namespace piezo::update::oe {

Covariance covariance(const FitAnswer& answer, Problem& prob, const OffsetWhitening& whiten,
                      double sigma, const TubeParams& nominal, const OeOptions& opt,
                      OeResult& out) {
  const LmOutcome& best = answer.best;
  const auto& t_best = answer.t;
  const double s2 = answer.s2;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Constant(kParams, kParams, NAN);
  if (best.jtj.rows() == kParams) {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(best.jtj);
    if (lu.isInvertible()) cov = s2 * lu.inverse();
  }
  const Eigen::VectorXd sx_stat = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  // Relative to the answer: nu12's coordinate is relative to the nominal.
  auto relative_to_answer = [&](Eigen::MatrixXd c) {
    const double k = nominal.nu12 / out.updated.nu12;
    if (c.rows() > 1) {
      c.row(1) *= k;
      c.col(1) *= k;
    }
    return c;
  };
  out.covariance_rel = relative_to_answer(cov);
  // Type-B part: the constants' shift per unit error of each chain quantity.
  if (t_best && best.jtj.rows() == kParams && cov.allFinite()) {
    const Eigen::MatrixXd& jb = best.j;  // weighted J at the answer
    const bool have_j = jb.rows() == out.residual_samples && jb.cols() == kParams;
    const Eigen::VectorXd r0 = prob.residual_of(*t_best);
    auto shifted = [&](double model::EffectSet::*field, double by) {
      model::EffectSet fx = prob.effects();
      fx.*field += by;
      return fx;
    };
    const std::pair<model::EffectSet, double> chain[] = {
        {shifted(&model::EffectSet::r1_tolerance, 1e-4), opt.r1_rel_sigma / 1e-4},
        {shifted(&model::EffectSet::parallel_capacitance_f, 1e-12), opt.cp_sigma_f / 1e-12},
        {shifted(&model::EffectSet::channel_gain, 1e-4), opt.gain_rel_sigma / 1e-4},
        {shifted(&model::EffectSet::channel_skew_s, 1e-9), opt.skew_sigma_s / 1e-9},
    };
    if (have_j) {
      const Eigen::MatrixXd jtj = jb.transpose() * jb;
      const auto ldlt = jtj.ldlt();
      for (const auto& [b, scale] : chain) {
        if (!(scale > 0)) continue;
        const auto tb = prob.transfer(best.x, b);
        if (!tb) continue;
        const Eigen::VectorXd drb = whiten(prob.residual_of(*tb) - r0) / sigma;  // ∂r/∂b·δb, weighted
        const Eigen::VectorXd dx = -ldlt.solve(jb.transpose() * drb) * scale;  // shift per 1 sigma of b
        if (dx.allFinite()) cov += dx * dx.transpose();
      }
    }
  }
  Eigen::VectorXd sx = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  return {std::move(cov), sx_stat, std::move(sx)};
}

void identify(const FitAnswer& answer, const Covariance& c, const TubeParams& nominal,
              const OeOptions& opt, OeResult& out) {
  const std::vector<LmOutcome>& runs = answer.runs;
  const LmOutcome& best = answer.best;
  const double s2 = answer.s2;
  const Eigen::MatrixXd& cov = c.cov;
  const Eigen::VectorXd &sx_stat = c.sx_stat, &sx = c.sx;
  const bool complex_loss = opt.damping == OeDamping::complex_constants;
  out.correlation = Eigen::MatrixXd::Identity(kParams, kParams);
  for (int a = 0; a < kParams; ++a)
    for (int b = 0; b < kParams; ++b)
      if (a != b) out.correlation(a, b) = cov(a, b) / (sx[a] * sx[b]);
  out.corr_nu12_d31 = out.correlation(1, 2);

  const TubeParams& u = out.updated;
  const double beta = out.damping.beta;
  struct Row {
    const char* name;
    const char* unit;
    double value, sigma, nominal;
    double limit;
  };
  const Row rows[kParams] = {
      {"YE11", "Pa", u.y_e11, u.y_e11 * sx[0], nominal.y_e11, opt.identifiable_rel_sigma},
      {"nu12", "-", u.nu12, nominal.nu12 * sx[1], nominal.nu12, opt.identifiable_rel_sigma},
      {"d31", "C/N", u.d31, std::abs(u.d31) * sx[2], nominal.d31, opt.identifiable_rel_sigma},
      {"epsT33_rel", "-", u.eps_t33 / model::kEps0, u.eps_t33 / model::kEps0 * sx[3],
       nominal.eps_t33 / model::kEps0, opt.identifiable_rel_sigma},
      complex_loss ? Row{"qm_inverse", "-", out.eta, out.eta * sx[4], opt.eta0, 0.5}
                   : Row{"beta", "s", beta, beta * sx[4], opt.beta0_s, 0.5},
  };
  if (complex_loss && out.eta > 0) {
    out.qm = 1.0 / out.eta;
    out.qm_sigma = out.qm * sx[4];  // the same relative sigma (first order in ln η)
  }
  for (int i = 0; i < kParams; ++i) {
    OeParameter p;
    p.name = rows[i].name;
    p.unit = rows[i].unit;
    p.value = rows[i].value;
    p.sigma = rows[i].sigma;
    p.sigma_statistical = rows[i].sigma * sx_stat[i] / sx[i];
    p.nominal = rows[i].nominal;
    p.status = "ok";
    char buf[400];
    const double rel = std::abs(p.sigma / p.value);
    if (!std::isfinite(p.sigma)) {
      p.status = "not identifiable";
      p.reason = "singular";
      p.note = "the data do not constrain it (singular normal equations): a longer record, a chirp or "
               "more shots";
    } else if (out.lack_of_fit) {
      p.status = "not identifiable";
      p.reason = "lack of fit";
      if (out.chi2_per_dof > out.chi2_limit)
        std::snprintf(buf, sizeof buf,
                      "the model class does not explain this capture (chi2/dof %.3g, the noise alone "
                      "allows up to %.3g): an effect outside the model biases every constant; find it "
                      "(gap diagnosis) or measure the fixture (calibration shots)",
                      out.chi2_per_dof, out.chi2_limit);
      else
        std::snprintf(buf, sizeof buf,
                      "the model class does not explain this capture in %.3g-%.3g kHz (residual power "
                      "%.3g times the noise's there, a chance of %s under noise alone; chi2/dof "
                      "%.3g overall): an effect outside the model (an end mass, a skew) biases every "
                      "constant; find it (gap diagnosis) or measure the fixture (calibration shots)",
                      out.band_lo_hz / 1e3, out.band_hi_hz / 1e3, out.band_excess,
                      dsp::probability_text(out.band_log10_p).c_str(), out.chi2_per_dof);
      p.note = buf;
    } else if (rel > rows[i].limit) {
      p.status = "not identifiable";
      p.reason = "sigma";
      std::snprintf(buf, sizeof buf,
                    "relative sigma %.3g %% exceeds the %.3g %% limit: more shots (sigma falls as "
                    "1/sqrt(shots)), less noise or a drive with more energy in the band would pin it",
                    100 * rel, 100 * rows[i].limit);
      p.note = buf;
    }
    // Another optimum the data cannot tell from the best (Δχ² < 4·s²) that puts
    // this constant more than 3 sigma away.
    for (std::size_t k = 1; k < runs.size() && p.status == "ok"; ++k) {
      if (2.0 * (runs[k].cost - best.cost) > 4.0 * s2) continue;
      const double dx = std::abs(runs[k].x[i] - best.x[i]);
      if (dx > 3.0 * sx_stat[i]) {
        p.status = "not identifiable";
        p.reason = "starts";
        std::snprintf(buf, sizeof buf,
                      "two starts reach equally good fits %.3g sigma apart: a chirp or a longer record "
                      "would separate them",
                      dx / sx_stat[i]);
        p.note = buf;
      }
    }
    out.parameters.push_back(p);
  }
}

}  // namespace piezo::update::oe
