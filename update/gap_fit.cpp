#include "update/gap_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>
#include <limits>
#include <stdexcept>

#include "numerics/levenberg_marquardt.hpp"

namespace piezo::update {

namespace {
constexpr double kStep = 1e-3;  // x units for the Jacobian
}

void GapData::validate(const char* who) const {
  const std::size_t n = f_hz.size();
  if (n < 8 || z_ohm.size() != n || sigma_log_mag.size() != n || sigma_phase.size() != n)
    throw std::invalid_argument(std::string(who) + ": gap data needs >= 8 points with Z and both uncertainties");
  for (std::size_t i = 0; i < n; ++i)
    if (!(f_hz[i] > 0) || !(sigma_log_mag[i] > 0) || !(sigma_phase[i] > 0) || !std::isfinite(std::abs(z_ohm[i])) ||
        z_ohm[i] == 0.0)
      throw std::invalid_argument(std::string(who) + ": gap data point " + std::to_string(i) +
                                  " has a non-positive frequency/uncertainty or a non-finite Z");
}

std::vector<double> gap_residuals(const GapModel& m, const GapData& d, const std::vector<double>& x) {
  const auto z = m.impedance(x, d.f_hz);
  std::vector<double> r(2 * d.size());
  for (std::size_t i = 0; i < d.size(); ++i) {
    const std::complex<double> l = std::log(d.z_ohm[i] / z[i]);
    r[2 * i] = l.real() / d.sigma_log_mag[i];
    r[2 * i + 1] = l.imag() / d.sigma_phase[i];
  }
  return r;
}

double gap_chi2(const GapModel& m, const GapData& d, const std::vector<double>& x) {
  double c = 0;
  try {
    for (double v : gap_residuals(m, d, x)) c += v * v;
  } catch (const std::invalid_argument&) {  // a non-physical material (coupling > 1, …): not a step to take
    return std::numeric_limits<double>::infinity();
  }
  return std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
}

std::vector<std::vector<double>> gap_jacobian(const GapModel& m, const GapData& d, const std::vector<double>& x,
                                              const std::vector<int>& columns) {
  std::vector<std::vector<double>> out;
  for (int j : columns) {
    std::vector<double> xp = x, xm = x;
    xp[static_cast<std::size_t>(j)] += kStep;
    xm[static_cast<std::size_t>(j)] -= kStep;
    // Central differences; at the edge of the physical domain (one side a
    // coupling factor > 1) the one-sided difference from the side that exists.
    std::optional<std::vector<double>> a, b;
    try {
      a = gap_residuals(m, d, xp);
    } catch (const std::invalid_argument&) {
    }
    try {
      b = gap_residuals(m, d, xm);
    } catch (const std::invalid_argument&) {
    }
    std::vector<double> col;
    if (a && b) {
      col = std::move(*a);
      for (std::size_t i = 0; i < col.size(); ++i) col[i] = (col[i] - (*b)[i]) / (2 * kStep);
    } else if (a || b) {
      const auto r0 = gap_residuals(m, d, x);  // throws where x itself is not physical
      col = a ? std::move(*a) : std::move(*b);
      const double h = a ? kStep : -kStep;
      for (std::size_t i = 0; i < col.size(); ++i) col[i] = (col[i] - r0[i]) / h;
    } else {
      (void)gap_residuals(m, d, xp);  // rethrows the reason
    }
    out.push_back(std::move(col));
  }
  return out;
}

GapFit fit_gap(GapModel& m, const GapData& d, const std::vector<double>& x0, const std::vector<bool>& free,
               const GapFitOptions& opt) {
  d.validate("fit_gap");
  const auto& info = m.params();
  if (x0.size() != info.size() || free.size() != info.size())
    throw std::invalid_argument("fit_gap: parameter vector does not match the model");
  std::vector<int> cols;
  for (int j = 0; j < static_cast<int>(free.size()); ++j)
    if (free[static_cast<std::size_t>(j)]) cols.push_back(j);
  const int p = static_cast<int>(cols.size());
  GapFit fit;
  fit.free = free;
  fit.x = x0;
  for (std::size_t j = 0; j < x0.size(); ++j) fit.x[j] = std::clamp(x0[j], info[j].lower, info[j].upper);
  fit.n = static_cast<int>(2 * d.size());
  fit.dof = fit.n - p;
  Eigen::MatrixXd jtj;
  for (int outer = 0; outer <= opt.max_relinearisations; ++outer) {
    // Levenberg–Marquardt (numerics/levenberg_marquardt) over the free columns.
    auto full = [&](const Eigen::VectorXd& u) {
      std::vector<double> x = fit.x;
      for (int c = 0; c < p; ++c) x[static_cast<std::size_t>(cols[static_cast<std::size_t>(c)])] = u[c];
      return x;
    };
    Eigen::VectorXd u0(p);
    for (int c = 0; c < p; ++c) u0[c] = fit.x[static_cast<std::size_t>(cols[static_cast<std::size_t>(c)])];
    numerics::LmProblem pb;
    pb.residual = [&](const Eigen::VectorXd& u) -> std::optional<Eigen::VectorXd> {
      try {
        const auto r = gap_residuals(m, d, full(u));
        return Eigen::Map<const Eigen::VectorXd>(r.data(), fit.n);
      } catch (const std::invalid_argument&) {  // a non-physical material (coupling > 1, …): not a step to take
        return std::nullopt;
      }
    };
    pb.jacobian = [&](const Eigen::VectorXd& u, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                      const numerics::LmJacobianCall&) {
      const auto jc = gap_jacobian(m, d, full(u), cols);  // throws where u itself is not physical
      j.resize(fit.n, p);
      for (int c = 0; c < p; ++c)
        j.col(c) = Eigen::Map<const Eigen::VectorXd>(jc[static_cast<std::size_t>(c)].data(), fit.n);
      return true;
    };
    pb.project = [&](Eigen::VectorXd& u) {
      for (int c = 0; c < p; ++c) {
        const auto& pi = info[static_cast<std::size_t>(cols[static_cast<std::size_t>(c)])];
        u[c] = std::clamp(u[c], pi.lower, pi.upper);
      }
    };
    numerics::LmSettings ls;  // this fit's damping before the shared engine
    ls.max_iterations = opt.max_iterations;
    ls.max_tries = 12;
    ls.mu_min = 1e-9;
    ls.diag_floor = 1e-12;
    ls.accept_equal = true;
    ls.relative_cost_tolerance = opt.chi2_tolerance;
    ls.cost_tolerance = 0.5e-6 * std::max(1.0, static_cast<double>(fit.n));  // Δχ² < 1e-6 per residual
    ls.tiny_rejected_step_converges = false;
    ls.on_stall = numerics::LmSettings::Stall::converged;  // no descent at any damping: a (local) minimum
    const numerics::LmRun run = numerics::levenberg_marquardt(pb, u0, ls);
    if (run.stop == numerics::LmRun::Stop::bad_start) (void)gap_residuals(m, d, fit.x);  // throws the reason
    fit.iterations += run.iterations;
    fit.x = full(run.x);
    if (run.j.rows() == fit.n) jtj = run.j.transpose() * run.j;
    fit.chi2 = 2.0 * run.cost;
    fit.converged = run.converged;

    // The linearised port model is accurate near its reference only.
    bool far = false;
    for (int i = 0; i < 4; ++i)
      if (free[static_cast<std::size_t>(i)]) far = true;
    if (!far || m.distance_from_linearisation(fit.x) < opt.relinearise_beyond) break;
    try {
      m.relinearise(fit.x);
    } catch (const std::invalid_argument& e) {  // the optimum sits at the edge of the physical domain
      fit.message = std::string("kept the previous linearisation: ") + e.what();
      break;
    }
    fit.chi2 = gap_chi2(m, d, fit.x);
  }
  if (!fit.converged && fit.message.empty())
    fit.message = "the gap fit did not converge in " + std::to_string(fit.iterations) + " iterations";
  fit.sigma_x.assign(info.size(), 0.0);
  if (p > 0 && jtj.rows() == p) {
    const Eigen::MatrixXd cov = jtj.completeOrthogonalDecomposition().pseudoInverse();
    const double scale = std::max(1.0, fit.chi2 / std::max(1, fit.dof));
    fit.covariance = cov * scale;
    for (int c = 0; c < p; ++c)
      fit.sigma_x[static_cast<std::size_t>(cols[static_cast<std::size_t>(c)])] = std::sqrt(std::max(0.0, cov(c, c) * scale));
  }
  return fit;
}

double predictive_chi2(const GapModel& m, const GapData& d, const GapFit& fit) {
  std::vector<int> cols;
  for (int j = 0; j < static_cast<int>(fit.free.size()); ++j)
    if (fit.free[static_cast<std::size_t>(j)]) cols.push_back(j);
  const auto r = gap_residuals(m, d, fit.x);
  if (cols.empty() || fit.covariance.rows() != static_cast<Eigen::Index>(cols.size())) {
    double c = 0;
    for (double v : r) c += v * v;
    return c;
  }
  const auto jc = gap_jacobian(m, d, fit.x, cols);
  const int p = static_cast<int>(cols.size());
  const auto n = static_cast<Eigen::Index>(r.size());
  // The held-out residuals' covariance is I + J C Jᵀ (their own unit noise
  // plus the fit's parameter uncertainty, which moves the prediction along a
  // few COHERENT patterns J·δθ). χ² = rᵀ(I + J C Jᵀ)⁻¹ r by Woodbury:
  //   rᵀr − (Jᵀr)ᵀ C (I + JᵀJ C)⁻¹ (Jᵀr).
  // Dividing each point by its own predictive variance instead (1 + j_iᵀ C j_i)
  // would count one poorly determined direction of the fit once per
  // held-out point that sees it: a 2σ deviation along it read as a gap
  // wherever the held-out drive is more sensitive than the fit's.
  Eigen::MatrixXd j(n, p);
  for (int c = 0; c < p; ++c) j.col(c) = Eigen::Map<const Eigen::VectorXd>(jc[static_cast<std::size_t>(c)].data(), n);
  const Eigen::VectorXd rv = Eigen::Map<const Eigen::VectorXd>(r.data(), n);
  const Eigen::VectorXd jr = j.transpose() * rv;
  const Eigen::MatrixXd m_inner = Eigen::MatrixXd::Identity(p, p) + (j.transpose() * j) * fit.covariance;
  const Eigen::VectorXd sol = m_inner.partialPivLu().solve(jr);
  const double chi = rv.squaredNorm() - jr.dot(fit.covariance * sol);
  return std::isfinite(chi) ? std::max(0.0, chi) : std::numeric_limits<double>::infinity();
}

}  // namespace piezo::update
