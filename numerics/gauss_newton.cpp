#include "numerics/gauss_newton.hpp"

#include <algorithm>
#include <cmath>

namespace piezo::numerics {

PenalisedGnResult penalised_gauss_newton(const PenalisedGnProblem& problem, const Eigen::MatrixXd& penalty,
                                         const Eigen::VectorXd& z0, const Eigen::VectorXd& r0, double cost0,
                                         const PenalisedGnSettings& settings) {
  PenalisedGnResult out{z0, r0, cost0, 0, 0};
  for (int it = 0; it < settings.max_iterations; ++it) {
    const auto w = problem.jacobian(out.z, out.r);
    ++out.iterations;
    if (!w) break;
    const Eigen::VectorXd g = w->transpose() * out.r + penalty * out.z;
    const Eigen::MatrixXd a = w->transpose() * *w + penalty;
    Eigen::VectorXd step = -a.ldlt().solve(g);
    if (!step.allFinite()) break;
    bool accepted = false, converged = false;
    for (int half = 0; half < settings.max_halvings && !accepted; ++half, step *= 0.5) {
      const Eigen::VectorXd zt = out.z + step;
      const auto rt = problem.residual(zt);
      if (!rt) continue;
      const double ct = rt->squaredNorm() + zt.dot(penalty * zt);
      if (ct < out.cost) {
        const double drop = out.cost - ct;
        out.z = zt;
        out.r = *rt;
        out.cost = ct;
        ++out.accepted;
        accepted = true;
        converged = drop < settings.min_drop;
      }
    }
    if (!accepted || converged) break;
  }
  return out;
}

int gauss_newton(const GaussNewtonProblem& problem, int max_iterations, double step_tolerance) {
  int it = 0;
  Eigen::VectorXd r;
  Eigen::MatrixXd j;
  for (; it < max_iterations; ++it) {
    problem.linearise(r, j);
    const Eigen::VectorXd step = problem.solve(j, -r);
    problem.apply(step);
    double d = 0;  // the largest |δ_i| (a NaN component does not count, as std::max skips it)
    for (Eigen::Index i = 0; i < step.size(); ++i) d = std::max(d, std::abs(step[i]));
    if (d < step_tolerance) {
      ++it;
      break;
    }
  }
  return it;
}

}  // namespace piezo::numerics
