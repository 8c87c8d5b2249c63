#include "numerics/levenberg_marquardt.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace piezo::numerics {

namespace {

double max_abs(const Eigen::VectorXd& v) { return v.size() ? v.cwiseAbs().maxCoeff() : 0.0; }

// max_p |step_p| / cap_p with LmSettings::max_step_each's caps (> 1: outside the trust region).
double over_caps(const Eigen::VectorXd& step, const Eigen::VectorXd& caps) {
  double k = 0;
  for (Eigen::Index p = 0; p < step.size(); ++p) k = std::max(k, std::abs(step[p]) / caps[p]);
  return k;
}

}  // namespace

LmRun levenberg_marquardt(const LmProblem& pb, Eigen::VectorXd x, const LmSettings& s) {
  if (!pb.residual || !pb.jacobian)
    throw std::invalid_argument("levenberg_marquardt: the problem needs a residual and a Jacobian");
  if (!(s.max_tries > 0) || !(s.mu0 > 0) || !(s.mu_down >= 1) || !(s.mu_up > 1))
    throw std::invalid_argument("levenberg_marquardt: tries, mu0 > 0, mu_down >= 1 and mu_up > 1 required");
  const bool per_coordinate = s.max_step_each.size() != 0;
  if (per_coordinate && (s.max_step_each.size() != x.size() || !(s.max_step_each.array() > 0).all()))
    throw std::invalid_argument("levenberg_marquardt: max_step_each needs one positive cap per coordinate");
  LmRun o;
  auto eval = [&](const Eigen::VectorXd& xt) {
    ++o.residuals;
    auto r = pb.residual(xt);
    if (r && !r->allFinite()) r.reset();
    return r;
  };
  auto cost_of = [](const std::optional<Eigen::VectorXd>& r) {
    return r ? 0.5 * r->squaredNorm() : std::numeric_limits<double>::infinity();
  };
  std::optional<Eigen::VectorXd> r = eval(x);
  if (!r) {
    o.stop = LmRun::Stop::bad_start;
    o.x = x;
    return o;
  }
  double cost = cost_of(r);
  if (x.size() == 0) {  // nothing free: the cost at x is the answer
    o.converged = true;
    o.stop = LmRun::Stop::converged;
    o.j.resize(r->size(), 0);
    o.x = std::move(x);
    o.r = std::move(*r);
    o.cost = cost;
    return o;
  }
  double mu = s.mu0, last_drop = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd& j = o.j;
  bool j_current = false;  // j is the Jacobian at x
  bool strict = false;     // this iteration again, on the exact J and unscreened (retry_exact)
  Eigen::VectorXd last_step = Eigen::VectorXd::Zero(x.size());
  auto screened = [&](const Eigen::VectorXd& anchor, const Eigen::VectorXd& xt) {
    return strict || !pb.screen ? std::numeric_limits<double>::quiet_NaN() : pb.screen(anchor, xt);
  };
  bool finished = false;
  int it = 1;
  for (; it <= s.max_iterations; ++it) {
    o.iterations = it;
    const double mu_it = mu;
    int evaluated_tries = 0;  // 0: every trial was refused by the screen
    ++o.jacobians;
    if (!pb.jacobian(x, *r, j, {it, strict})) {
      o.stop = LmRun::Stop::jacobian_failed;
      j_current = false;
      finished = true;
      break;
    }
    j_current = true;
    const Eigen::MatrixXd jtj = j.transpose() * j;
    const Eigen::VectorXd g = j.transpose() * *r;
    bool accepted = false, done = false;
    for (int tries = 0; tries < s.max_tries && !accepted; ++tries) {
      Eigen::MatrixXd a = jtj;
      for (Eigen::Index p = 0; p < a.rows(); ++p) a(p, p) += mu * std::max(jtj(p, p), s.diag_floor);
      Eigen::VectorXd step = a.ldlt().solve(-g);
      if (per_coordinate) {
        const double over = over_caps(step, s.max_step_each);
        if (over > 1) step /= over;
      } else {
        const double big = max_abs(step);
        if (big > s.max_step) step *= s.max_step / big;
      }
      Eigen::VectorXd trial = x + step;
      if (pb.project) pb.project(trial);
      if (screened(x, trial) >= cost) {
        mu *= s.mu_up;
        // The screen alone never ends a run: the exact J decides (retry_exact).
        if (max_abs(step) < s.step_tolerance) break;
        continue;
      }
      ++evaluated_tries;
      auto rt = eval(trial);
      const double ct = cost_of(rt);
      const bool lower = std::isfinite(ct) && (s.accept_equal ? ct <= cost : ct < cost);
      if (lower) {
        const Eigen::VectorXd x_old = x;
        x = trial;
        r = std::move(rt);
        j_current = false;
        double c_new = ct;
        Eigen::VectorXd ext = step;
        for (int d = 0; d < s.extend_steps && mu < s.extend_below_mu; ++d) {
          ext *= 2.0;
          if (per_coordinate ? over_caps(ext, s.max_step_each) > 1 : max_abs(ext) > s.max_step) break;
          Eigen::VectorXd xe = x_old + ext;
          if (pb.project) pb.project(xe);
          if (screened(x, xe) >= c_new) break;
          auto re = eval(xe);
          const double ce = cost_of(re);
          if (!(ce < c_new)) break;
          x = xe;
          r = std::move(re);
          c_new = ce;
        }
        const double drop = cost - c_new;
        const double rel = drop / std::max(cost, 1e-300);
        last_drop = drop;
        cost = c_new;
        last_step = step;
        mu = std::max(mu / s.mu_down, s.mu_min);
        accepted = true;
        done = max_abs(step) < s.step_tolerance || drop < s.cost_tolerance ||
               rel < s.relative_cost_tolerance;
        if (!done && pb.converged_after_step)
          done = pb.converged_after_step(LmState{x, last_step, cost, last_drop, it});
      } else {
        mu *= s.mu_up;
        if (s.tiny_rejected_step_converges && max_abs(step) < s.step_tolerance) accepted = done = true;
      }
    }
    if (done) {
      o.converged = true;
      o.stop = LmRun::Stop::converged;
      finished = true;
      break;
    }
    if (!accepted) {
      if (s.retry_exact && !strict) {
        strict = true;
        if (evaluated_tries == 0) mu = mu_it;  // the screen's refusals grew μ, not the data
        --it;
        continue;
      }
      double cosine = 0;
      for (Eigen::Index p = 0; p < g.size(); ++p)
        cosine = std::max(cosine, std::abs(g[p]) / std::sqrt(jtj(p, p) * 2.0 * cost + 1e-300));
      o.stall_cosine = cosine;
      const bool minimum = s.on_stall == LmSettings::Stall::converged ||
                           (s.on_stall == LmSettings::Stall::gradient_cosine && cosine < s.stall_cosine);
      o.converged = minimum;
      o.stop = minimum ? LmRun::Stop::converged : LmRun::Stop::stalled;
      finished = true;
      break;
    }
    strict = false;
    if (pb.after_iteration) {
      auto v = pb.after_iteration(LmState{x, last_step, cost, last_drop, it});
      if (v.stop) {
        o.converged = v.converged;
        o.stop = v.converged ? LmRun::Stop::converged : LmRun::Stop::stopped_by_caller;
        o.message = std::move(v.message);
        finished = true;
        break;
      }
    }
  }
  if (!finished) {
    o.iterations = s.max_iterations;
    o.stop = LmRun::Stop::iteration_limit;
  }
  if (s.jacobian_at_answer && !j_current && o.stop != LmRun::Stop::jacobian_failed) {
    ++o.jacobians;
    if (!pb.jacobian(x, *r, j, {o.iterations, true})) j.resize(0, 0);
  }
  o.x = std::move(x);
  o.r = std::move(*r);
  o.cost = cost;
  return o;
}

bool forward_difference_jacobian(
    const std::function<std::optional<Eigen::VectorXd>(const Eigen::VectorXd&)>& residual,
    const Eigen::VectorXd& x, const Eigen::VectorXd& r, const Eigen::VectorXd& h, Eigen::MatrixXd& j) {
  if (h.size() != x.size())
    throw std::invalid_argument("forward_difference_jacobian: one step per coordinate required");
  j.resize(r.size(), x.size());
  for (Eigen::Index c = 0; c < x.size(); ++c) {
    Eigen::VectorXd xp = x;
    xp[c] += h[c];
    auto rp = residual(xp);
    if (rp && rp->allFinite()) {
      j.col(c) = (*rp - r) / h[c];
      continue;
    }
    xp[c] = x[c] - h[c];
    rp = residual(xp);
    if (!rp || !rp->allFinite()) return false;
    j.col(c) = (r - *rp) / h[c];
  }
  return true;
}

Eigen::MatrixXd lm_covariance(const Eigen::MatrixXd& j) {
  return (j.transpose() * j).completeOrthogonalDecomposition().pseudoInverse();
}

}  // namespace piezo::numerics
