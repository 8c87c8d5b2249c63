// The optimiser (fitter.hpp): weighted residual, Jacobian, the LM loop, the
// exact J at an answer.
#include "update/output_error/fitter.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>

#include "numerics/levenberg_marquardt.hpp"

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
  numerics::LmProblem pb;
  pb.residual = [&](const Eigen::VectorXd& xt) { return weighted(xt); };
  // J by forward differences at every iterate: four FE port models (β's
  // column reuses the cached one), or none near the last exact J (the port
  // models' tangent, Problem::set_tangent). Broyden's rank-one updates instead
  // were measured on the corpus: fewer models on the first start, but later
  // starts crawl and can look stalled where the exact J joins the best optimum.
  // A retry (the engine's retry_exact: an iteration that found no lower cost
  // through the tangent, j0's frozen columns or the screen) is exact.
  pb.jacobian = [&](const Eigen::VectorXd& xt, const Eigen::VectorXd& r, Eigen::MatrixXd& j,
                    const numerics::LmJacobianCall& call) {
    const bool have_j0 = j0 && j0->rows() == r.size() && j0->cols() == xt.size();
    if (call.exact) return jacobian(xt, r, j, 0, true);
    if (call.iteration == 1 && have_j0) {
      j = *j0;
      return true;
    }
    if (freeze_material && have_j0) {
      j = *j0;
      return jacobian(xt, r, j, 4);
    }
    return jacobian(xt, r, j);
  };
  // A trial near x is screened on the tangent anchored at x first (its model
  // exact at x, the slopes x_ref's): a step it says raises the cost is
  // rejected without an FE model; one it says lowers it is computed.
  pb.screen = [&](const Eigen::VectorXd& anchor, const Eigen::VectorXd& xt) { return tangent_cost(anchor, xt); };
  // A later start stops early inside the lead's optimum, or stalled far above it.
  pb.after_iteration = [&](const numerics::LmState& st) {
    numerics::LmVerdict v;
    if (!lead || lead->jtj.rows() != st.x.size() || lead->x.size() != st.x.size()) return v;
    const Eigen::VectorXd dx = st.x - lead->x;
    const double gap = st.cost - lead->cost;
    if (gap >= 0 && dx.dot(lead->jtj * dx) < 9.0) return numerics::LmVerdict{true, true, "joined the first start's optimum"};
    const double s2 = std::max(1.0, 2.0 * lead->cost / dof_fit);
    if (st.iteration >= 2 && gap > std::max(50.0, 10.0 * s2) && st.last_drop < 0.1 * gap)
      return numerics::LmVerdict{true, false, "stalled far above the first start's optimum"};
    return v;
  };
  numerics::LmSettings ls;  // this fit's damping, as measured on the corpus before the shared engine
  ls.max_iterations = opt.max_iterations;
  ls.max_tries = 14;
  ls.max_step = 0.3;  // trust region: no constant moves by more than 30 % in one step
  if (x.size() > kParams) {  // an effect scanned (a sixth coordinate, in typical sizes): its own bound
    ls.max_step_each = Eigen::VectorXd::Constant(x.size(), ls.max_step);
    ls.max_step_each.tail(x.size() - kParams).setConstant(opt.effect_max_step);
  }
  // The cost is ½χ²: a decrease below 1e-2 leaves the estimate within ~0.15
  // of its sigma of the optimum.
  ls.step_tolerance = opt.step_tolerance;
  ls.cost_tolerance = opt.cost_tolerance;
  ls.retry_exact = true;
  // Along a curved valley (resonances sliding into place) the Gauss-Newton
  // step is far shorter than the way to the minimum: go on along it, doubling.
  ls.extend_steps = 4;
  ls.jacobian_at_answer = false;  // finish() computes the exact J of the run that is used
  const numerics::LmRun run = numerics::levenberg_marquardt(pb, std::move(x), ls);
  LmOutcome o;
  o.x = run.x;
  o.iterations = run.iterations;
  o.converged = run.converged;
  o.message = run.message;
  switch (run.stop) {
    case numerics::LmRun::Stop::bad_start:
      o.message = "the start cannot be simulated";
      o.cost = INFINITY;
      return o;
    case numerics::LmRun::Stop::jacobian_failed:
      o.message = "the model could not be simulated near the estimate";
      break;
    case numerics::LmRun::Stop::stalled:
      o.message = "no decrease of the output error (gradient cosine " + std::to_string(run.stall_cosine) + ")";
      break;
    default:
      break;
  }
  if (!o.converged && o.message.empty())
    o.message = "did not converge in " + std::to_string(opt.max_iterations) + " iterations";
  o.cost = run.cost;
  o.r = run.r;
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
