// The optimiser (fitter.hpp): weighted residual, Jacobian, the LM loop, the
// exact J at an answer.
#include "update/output_error/fitter.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

namespace piezo::update::oe {

std::optional<Eigen::VectorXd> Fitter::weighted(const Eigen::VectorXd& x) {
  auto r = prob.residual(x);
  if (!r) return std::nullopt;
  *r = whiten(std::move(*r)) / sigma;
  if (!r->allFinite()) return std::nullopt;
  return r;
}

bool Fitter::jacobian(const Eigen::VectorXd& x, const Eigen::VectorXd& r0, Eigen::MatrixXd& j,
                      int first, bool exact) {
  const auto np = static_cast<int>(x.size());  // 5, or 6 with a free effect (scan_effects)
  if (j.rows() != r0.size() || j.cols() != np) {
    j.resize(r0.size(), np);
    first = 0;
  }
  const bool tangent = !exact && first < 4 && prob.tangent_near(x);
  {  // the columns' port models at once (the constants' unless through the tangent)
    std::vector<std::pair<Eigen::VectorXd, double>> points;
    for (int c = first; c < np; ++c) {
      if (c < 4 && tangent) continue;
      Eigen::VectorXd xp = x;
      xp[c] += c >= 4 ? 1e-4 : 1e-6;
      points.emplace_back(xp, prob.effects_at(xp).mass_loading);
    }
    if (points.size() > 1) prob.prefetch(points);
  }
  for (int c = first; c < np; ++c) {
    const double h = c >= 4 ? 1e-4 : 1e-6;
    if (c < 4 && tangent) {
      if (const auto tt = prob.tangent_transfer(x, c, h)) {
        const Eigen::VectorXd rt = whiten(prob.residual_of(*tt)) / sigma;
        if (rt.allFinite()) {
          j.col(c) = (rt - r0) / h;
          continue;
        }
      }
    }
    Eigen::VectorXd xp = x;
    xp[c] += h;
    auto rp = weighted(xp);
    if (!rp) {
      xp[c] = x[c] - h;  // the other side
      rp = weighted(xp);
      if (!rp) return false;
      j.col(c) = (r0 - *rp) / h;
    } else {
      j.col(c) = (*rp - r0) / h;
    }
  }
  if (first == 0 && !tangent) prob.set_tangent(x, 1e-6);
  return true;
}

double Fitter::tangent_cost(const Eigen::VectorXd& anchor, const Eigen::VectorXd& x) {
  const auto t = prob.tangent_model(anchor, x);
  if (!t) return NAN;
  const Eigen::VectorXd r = whiten(prob.residual_of(*t)) / sigma;
  return r.allFinite() ? 0.5 * r.squaredNorm() : NAN;
}

LmOutcome Fitter::levenberg_marquardt(Eigen::VectorXd x, const LmOutcome* lead,
                                      const Eigen::MatrixXd* j0, bool freeze_material) {
  LmOutcome o;
  auto r = weighted(x);
  if (!r) {
    o.message = "the start cannot be simulated";
    o.cost = INFINITY;
    o.x = x;
    return o;
  }
  double cost = 0.5 * r->squaredNorm();
  double mu = 1e-3, last_drop = INFINITY;
  // J by forward differences at every iterate: four FE port models (β's
  // column reuses the cached one), or none near the last exact J (the
  // port models' tangent, Problem::set_tangent). Broyden's rank-one updates
  // instead were measured on the corpus: fewer models on the first start,
  // but later starts crawl and can look stalled where the exact J joins the
  // best optimum.
  Eigen::MatrixXd j;
  // An iteration that finds no lower cost (its J perhaps through the
  // tangent or j0's frozen columns, its trials screened) runs again on the
  // exact J, unscreened, before the run gives up.
  bool strict = false;
  for (int it = 1; it <= opt.max_iterations; ++it) {
    o.iterations = it;
    const double mu_it = mu;
    int exact_tries = 0;  // none: every try was refused by the tangent's screen
    const bool have_j0 = j0 && j0->rows() == r->size() && j0->cols() == x.size();
    bool j_ok = true;
    if (strict) {
      j_ok = jacobian(x, *r, j, 0, true);
    } else if (it == 1 && have_j0) {
      j = *j0;
    } else if (freeze_material && have_j0) {
      j = *j0;
      j_ok = jacobian(x, *r, j, 4);
    } else {
      j_ok = jacobian(x, *r, j);
    }
    if (!j_ok) {
      o.message = "the model could not be simulated near the estimate";
      break;
    }
    const Eigen::MatrixXd jtj = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * *r;
    bool accepted = false, done = false;
    // A trial near x is screened on the tangent anchored at x first (its
    // model exact at x, the slopes x_ref's): a step it says raises the cost
    // is rejected without an FE model; one it says lowers it is computed.
    auto screen = [&](const Eigen::VectorXd& anchor, const Eigen::VectorXd& xt) {
      return strict ? NAN : tangent_cost(anchor, xt);
    };
    for (int tries = 0; tries < 14 && !accepted; ++tries) {
      Eigen::MatrixXd a = jtj;
      for (Eigen::Index p = 0; p < a.rows(); ++p) a(p, p) += mu * std::max(jtj(p, p), 1e-300);
      Eigen::VectorXd step = a.ldlt().solve(-g);
      // Trust region: no constant moves by more than 30 % in one step.
      const double big = step.cwiseAbs().maxCoeff();
      if (big > 0.3) step *= 0.3 / big;
      const Eigen::VectorXd trial = x + step;
      if (screen(x, trial) >= cost) {
        mu *= 4.0;
        // The screen alone never ends a run (its slopes are x_ref's): the
        // exact J decides (strict, below).
        if (step.cwiseAbs().maxCoeff() < opt.step_tolerance) break;
        continue;
      }
      ++exact_tries;
      const auto rt = weighted(trial);
      const double ct = rt ? 0.5 * rt->squaredNorm() : INFINITY;
      if (ct < cost) {
        const Eigen::VectorXd x_old = x;
        x = trial;
        r = rt;
        double c_new = ct;
        // Along a curved valley (resonances sliding into place) the
        // Gauss-Newton step is far shorter than the way to the minimum: go
        // on along it, doubling, while the cost keeps falling (one model per
        // try instead of a Jacobian per step; screened as above).
        Eigen::VectorXd ext = step;
        for (int d = 0; d < 4 && mu < 1e-2; ++d) {
          ext *= 2.0;
          if (ext.cwiseAbs().maxCoeff() > 0.3) break;
          const Eigen::VectorXd xe = x_old + ext;
          if (screen(x, xe) >= c_new) break;
          const auto re = weighted(xe);
          const double ce = re ? 0.5 * re->squaredNorm() : INFINITY;
          if (!(ce < c_new)) break;
          x = xe;
          r = re;
          c_new = ce;
        }
        const double drop = cost - c_new;
        last_drop = drop;
        cost = c_new;
        mu = std::max(mu / 3.0, 1e-12);
        accepted = true;
        // The cost is ½χ²: a decrease below 1e-2 leaves the estimate
        // within ~0.15 of its sigma of the optimum.
        done = step.cwiseAbs().maxCoeff() < opt.step_tolerance || drop < opt.cost_tolerance;
      } else {
        mu *= 4.0;
        if (step.cwiseAbs().maxCoeff() < opt.step_tolerance) accepted = done = true;
      }
    }
    if (done) {
      o.converged = true;
      break;
    }
    if (!accepted) {
      if (!strict) {
        strict = true;
        if (exact_tries == 0) mu = mu_it;  // (the screen's refusals grew mu, not the data)
        --it;
        continue;
      }
      double cosine = 0;
      for (Eigen::Index p = 0; p < g.size(); ++p)
        cosine = std::max(cosine, std::abs(g[p]) / std::sqrt(jtj(p, p) * 2.0 * cost + 1e-300));
      if (cosine < 1e-4) {
        o.converged = true;
      } else {
        o.message = "no decrease of the output error (gradient cosine " + std::to_string(cosine) + ")";
      }
      break;
    }
    strict = false;
    if (lead && lead->jtj.rows() == x.size() && lead->x.size() == x.size()) {
      const Eigen::VectorXd dx = x - lead->x;
      const double gap = cost - lead->cost;
      if (gap >= 0 && dx.dot(lead->jtj * dx) < 9.0) {
        o.converged = true;
        o.message = "joined the first start's optimum";
        break;
      }
      const double s2 = std::max(1.0, 2.0 * lead->cost / dof_fit);
      if (it >= 2 && gap > std::max(50.0, 10.0 * s2) && last_drop < 0.1 * gap) {
        o.message = "stalled far above the first start's optimum";
        break;
      }
    }
  }
  if (!o.converged && o.message.empty())
    o.message = "did not converge in " + std::to_string(opt.max_iterations) + " iterations";
  o.x = x;
  o.cost = cost;
  o.r = *r;
  return o;
}

void Fitter::finish(LmOutcome& o) {
  Eigen::MatrixXd j;
  if (o.r.size() > 0 && jacobian(o.x, o.r, j, 0, true)) {
    o.j = j;
    o.jtj = j.transpose() * j;
  }
}

}  // namespace piezo::update::oe
