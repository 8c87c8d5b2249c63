// The shots' consistency before pooling (shot_consistency.hpp).
//
// Shot k's residual at the pooled answer x̂ is r̂ + L ∗ (T ∗ d1_k − d2_k)
// (d_k: the shot minus the average), weighted by one shot's noise σ_k: the
// shots' scatter orthogonal to the constants' directions. One Gauss–Newton step on the answer's Jacobian J_k = J·σ/σ_k gives its
// constants δx_k = −(J_kᵀJ_k)⁻¹J_kᵀz_k with covariance C_k = (J_kᵀJ_k)⁻¹ —
// exact to first order in the shots' differences (a few per cent). Their
// homogeneity χ² = Σ (δx_k − x̄)ᵀC_k⁻¹(δx_k − x̄) has (K − 1)·5 degrees of
// freedom; per constant, a line over the shot index (drift) and the best
// split into two means (step) are each compared with a constant by the χ²
// they remove.
#include "dsp/uncertain_text.hpp"
#include "dsp/probability_text.hpp"
#include "update/output_error/shot_consistency.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "update/residual_regions.hpp"

namespace piezo::update::oe {

namespace {

// Δχ² a drift or a step must remove (one parameter, several constants and
// splits tried): p ≈ 1e-4 before the splits' Bonferroni factor.
constexpr double kChangeChi2 = 15.1;

struct Series {
  std::vector<double> y, s;  // per shot: value and sigma
};

double chi2_constant(const Series& a, std::size_t lo, std::size_t hi, double& mean, double& wsum) {
  double sw = 0, swy = 0;
  for (std::size_t k = lo; k < hi; ++k) {
    const double w = 1.0 / (a.s[k] * a.s[k]);
    sw += w;
    swy += w * a.y[k];
  }
  mean = swy / sw;
  wsum = sw;
  double c = 0;
  for (std::size_t k = lo; k < hi; ++k) c += (a.y[k] - mean) * (a.y[k] - mean) / (a.s[k] * a.s[k]);
  return c;
}

}  // namespace

OeShotConsistency shot_consistency(const FitAnswer& answer, Problem& prob, const OffsetWhitening& whiten,
                                   const Averaged& rec, double sigma, double nu12_scale,
                                   const std::vector<OeParameter>& parameters) {
  OeShotConsistency out;
  out.jitter_samples = rec.jitter_samples;
  out.aligned = rec.aligned;
  const int K = rec.shots;
  const Eigen::MatrixXd& j = answer.best.j;
  if (K < 2 || rec.dev1.size() != static_cast<std::size_t>(K) ||
      !answer.t || j.cols() != kParams || j.rows() == 0 || !(sigma > 0) || parameters.size() < kParams)
    return out;
  const Eigen::VectorXd r0 = prob.residual_of(*answer.t);
  // One shot's noise in the fit's own metric: the shots' scatter ORTHOGONAL
  // to the constants' directions (a drift or a step of the constants lives in
  // span J to first order and does not inflate it; a noise that is not white,
  // which the pretrigger's std would misjudge, is measured as it is).
  const Eigen::MatrixXd jr = j * sigma;  // ∂(whitened residual, volts)/∂x
  const Eigen::LDLT<Eigen::MatrixXd> pj((jr.transpose() * jr).eval());
  std::vector<Eigen::VectorXd> devs;
  double ss = 0;
  for (int k = 0; k < K; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    devs.push_back(whiten(prob.deviation(*answer.t, rec.dev1[ku], rec.dev2[ku])));
    const Eigen::VectorXd e = devs.back() - jr * pj.solve(jr.transpose() * devs.back());
    ss += e.squaredNorm();
  }
  const double free_dims = double(j.rows()) - kParams - whiten.dof;
  if (!(free_dims > 0)) return out;
  const double sk = std::sqrt(ss / (double(K - 1) * free_dims));
  const Eigen::VectorXd w0 = whiten(r0);
  std::vector<Eigen::VectorXd> dx;
  std::vector<Eigen::MatrixXd> cinv, cov;
  for (int k = 0; k < K; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    if (!(sk > 0) || !std::isfinite(sk)) return out;
    const Eigen::VectorXd z = (w0 + devs[ku]) / sk;
    const Eigen::MatrixXd jk = j * (sigma / sk);
    const Eigen::MatrixXd a = jk.transpose() * jk;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
    if (ldlt.info() != Eigen::Success) return out;
    dx.push_back(-ldlt.solve(jk.transpose() * z));
    cinv.push_back(a);
    cov.push_back(ldlt.solve(Eigen::MatrixXd::Identity(kParams, kParams)));
    if (!dx.back().allFinite() || !cov.back().allFinite()) return out;
  }
  // nu12's coordinate is relative to the nominal: relative to the answer.
  for (int k = 0; k < K; ++k) {
    dx[static_cast<std::size_t>(k)][1] *= nu12_scale;
    cov[static_cast<std::size_t>(k)].row(1) *= nu12_scale;
    cov[static_cast<std::size_t>(k)].col(1) *= nu12_scale;
    cinv[static_cast<std::size_t>(k)].row(1) /= nu12_scale;
    cinv[static_cast<std::size_t>(k)].col(1) /= nu12_scale;
  }
  out.tested = true;
  out.shots = K;
  Eigen::MatrixXd w = Eigen::MatrixXd::Zero(kParams, kParams);
  Eigen::VectorXd wy = Eigen::VectorXd::Zero(kParams);
  for (int k = 0; k < K; ++k) {
    w += cinv[static_cast<std::size_t>(k)];
    wy += cinv[static_cast<std::size_t>(k)] * dx[static_cast<std::size_t>(k)];
  }
  const Eigen::VectorXd mean = w.ldlt().solve(wy);
  for (int k = 0; k < K; ++k) {
    const Eigen::VectorXd e = dx[static_cast<std::size_t>(k)] - mean;
    out.chi2 += e.dot(cinv[static_cast<std::size_t>(k)] * e);
  }
  out.dof = (K - 1) * kParams;
  out.log10_p = std::min(0.0, log_gamma_tail((out.dof + 1) / 2, 0.5 * out.chi2) / std::log(10.0));
  // Consistent unless the chance is below 1e-6: the per-shot constants are
  // linear about the pooled answer, and under a large misfit of the model
  // (test_gap_validation's 15 ohm lead, 16 shots of one tube) their scatter
  // came out at 1e-4; the studies' drifts and steps of 0.5-2 % stood at
  // 1e-20 and far below.
  out.consistent = out.log10_p > -6.0;
  out.per_shot_sigma_pct.assign(kParams, 0.0);
  for (int k = 0; k < K; ++k) {
    std::vector<double> row(kParams);
    for (int c = 0; c < kParams; ++c) {
      row[static_cast<std::size_t>(c)] = 100.0 * dx[static_cast<std::size_t>(k)][c];
      out.per_shot_sigma_pct[static_cast<std::size_t>(c)] +=
          100.0 * std::sqrt(std::max(0.0, cov[static_cast<std::size_t>(k)](c, c))) / K;
    }
    out.per_shot_pct.push_back(std::move(row));
  }
  if (out.consistent) return out;

  // Per constant: drift (a line over the shot index) or step (two means).
  const double split_penalty = 2.0 * std::log(std::max(1, K - 2) + 0.0);
  for (int c = 0; c < kParams; ++c) {
    Series a;
    for (int k = 0; k < K; ++k) {
      a.y.push_back(dx[static_cast<std::size_t>(k)][c]);
      a.s.push_back(std::sqrt(std::max(1e-300, cov[static_cast<std::size_t>(k)](c, c))));
    }
    double m0, w0;
    const double chi0 = chi2_constant(a, 0, a.y.size(), m0, w0);
    // drift
    double sw = 0, swx = 0;
    for (std::size_t k = 0; k < a.y.size(); ++k) {
      const double wk = 1.0 / (a.s[k] * a.s[k]);
      sw += wk;
      swx += wk * double(k);
    }
    const double xbar = swx / sw;
    double sxx = 0, sxy = 0;
    for (std::size_t k = 0; k < a.y.size(); ++k) {
      const double wk = 1.0 / (a.s[k] * a.s[k]);
      sxx += wk * (double(k) - xbar) * (double(k) - xbar);
      sxy += wk * (double(k) - xbar) * (a.y[k] - m0);
    }
    const double slope = sxx > 0 ? sxy / sxx : 0.0, slope_sigma = sxx > 0 ? 1.0 / std::sqrt(sxx) : INFINITY;
    const double gain_drift = sxx > 0 ? slope * slope * sxx : 0.0;
    // step
    double gain_step = 0, step = 0, step_sigma = INFINITY;
    int split = -1;
    for (std::size_t m = 1; m < a.y.size(); ++m) {
      double m1, w1, m2, w2;
      const double c1 = chi2_constant(a, 0, m, m1, w1), c2 = chi2_constant(a, m, a.y.size(), m2, w2);
      const double g = chi0 - c1 - c2;
      if (g > gain_step) {
        gain_step = g;
        step = m2 - m1;
        step_sigma = std::sqrt(1.0 / w1 + 1.0 / w2);
        split = static_cast<int>(m) - 1;
      }
    }
    OeShotChange ch;
    ch.parameter = parameters[static_cast<std::size_t>(c)].name;
    const bool step_better = gain_step - split_penalty > gain_drift;
    if (step_better && gain_step - split_penalty > kChangeChi2) {
      ch.kind = "step";
      ch.size_pct = 100.0 * step;
      ch.sigma_pct = 100.0 * step_sigma;
      ch.after_shot = rec.index[static_cast<std::size_t>(split)];
    } else if (!step_better && gain_drift > kChangeChi2) {
      ch.kind = "drift";
      ch.size_pct = 100.0 * slope * (K - 1);
      ch.sigma_pct = 100.0 * slope_sigma * (K - 1);
    } else {
      continue;
    }
    ch.z = ch.sigma_pct > 0 ? std::abs(ch.size_pct) / ch.sigma_pct : 0.0;
    out.changes.push_back(ch);
  }
  std::sort(out.changes.begin(), out.changes.end(),
            [](const OeShotChange& a, const OeShotChange& b) { return a.z > b.z; });
  char buf[300];
  std::snprintf(buf, sizeof buf, "The %d shots disagree (homogeneity chi2 %.0f for %d dof, chance %s)", K,
                out.chi2, out.dof, dsp::probability_text(out.log10_p).c_str());
  out.summary = buf;
  if (out.changes.empty()) {
    out.summary += ": no single constant's drift or step stands out.";
  } else {
    out.summary += ":";
    for (std::size_t i = 0; i < out.changes.size(); ++i) {
      const auto& ch = out.changes[i];
      if (ch.kind == "step")
        std::snprintf(buf, sizeof buf, " %s step %s between shots %d and %d", ch.parameter.c_str(),
                      dsp::format_uncertain(ch.size_pct, ch.sigma_pct, "%").c_str(), ch.after_shot, ch.after_shot + 1);
      else
        std::snprintf(buf, sizeof buf, " %s drift %s over the %d shots", ch.parameter.c_str(),
                      dsp::format_uncertain(ch.size_pct, ch.sigma_pct, "%").c_str(), K);
      out.summary += std::string(i ? ";" : "") + buf;
    }
    out.summary += ".";
  }
  out.summary += " They were pooled (averaged) all the same: the constants are the shots' mean state.";
  return out;
}

}  // namespace piezo::update::oe
