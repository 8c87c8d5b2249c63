#include "dsp/bvd_fit.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "numerics/complex_division.hpp"
#include "numerics/levenberg_marquardt.hpp"

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

void check_range(const char* fn, const Eigen::VectorXd& f, Eigen::Index first, Eigen::Index last) {
  if (first < 0 || last >= f.size() || last - first + 1 < 3)
    throw std::invalid_argument(std::string(fn) + ": need at least 3 points inside the grid");
}
}  // namespace

cd BvdParams::motional_admittance(double f_hz) const {
  const cd s(0.0, kTwoPi * f_hz);
  // (numerics/complex_division.hpp: no libgcc call in the circuit fits' loop)
  return numerics::reciprocal(r1_ohm + s * l1_h + numerics::reciprocal(s * c1_f));
}

cd BvdParams::admittance(double f_hz) const {
  return cd(0.0, kTwoPi * f_hz * c0_f) + motional_admittance(f_hz);
}

AdmittanceCircle fit_admittance_circle(const Eigen::VectorXcd& y) {
  const Eigen::Index n = y.size();
  if (n < 3) throw std::invalid_argument("fit_admittance_circle: need at least 3 points");
  // Centred and scaled for conditioning; x² + y² + D x + E y + F = 0 is linear in D, E, F.
  const cd mean = y.mean();
  double scale = 0;
  for (Eigen::Index k = 0; k < n; ++k) scale = std::max(scale, std::abs(y[k] - mean));
  if (!(scale > 0)) throw std::invalid_argument("fit_admittance_circle: the points coincide");
  Eigen::MatrixXd a(n, 3);
  Eigen::VectorXd b(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd u = (y[k] - mean) / scale;
    a.row(k) << u.real(), u.imag(), 1.0;
    b[k] = -std::norm(u);
  }
  const Eigen::Vector3d d = a.colPivHouseholderQr().solve(b);
  const cd c(-d[0] / 2, -d[1] / 2);
  AdmittanceCircle out;
  out.centre = mean + scale * c;
  out.radius = scale * std::sqrt(std::max(0.0, std::norm(c) - d[2]));
  double s2 = 0;
  for (Eigen::Index k = 0; k < n; ++k) s2 += std::pow(std::abs(y[k] - out.centre) - out.radius, 2);
  out.rms_distance = std::sqrt(s2 / double(n));
  return out;
}

BvdParams bvd_start_from_circle(const Eigen::VectorXd& f, const Eigen::VectorXcd& y,
                                Eigen::Index first, Eigen::Index last) {
  check_range("bvd_start_from_circle", f, first, last);
  const Eigen::Index n = last - first + 1;
  const auto circle = fit_admittance_circle(y.segment(first, n));
  BvdParams p;
  p.r1_ohm = 1.0 / (2.0 * circle.radius);
  // Reactance of each point from its angle on the circle, then X = ωL1 − (1/C1)/ω.
  Eigen::MatrixXd a(n, 2);
  Eigen::VectorXd x(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double w = kTwoPi * f[first + k];
    const double phi = -0.5 * std::arg(y[first + k] - circle.centre);
    x[k] = p.r1_ohm * std::tan(phi);
    a.row(k) << w, -1.0 / w;
  }
  // Scale the columns so both unknowns are O(1) to the solver.
  const double s0 = a.col(0).norm(), s1 = a.col(1).norm();
  a.col(0) /= s0;
  a.col(1) /= s1;
  const Eigen::Vector2d sol = a.colPivHouseholderQr().solve(x);
  p.l1_h = sol[0] / s0;
  p.c1_f = s1 / sol[1];
  const double ws = 1.0 / std::sqrt(p.l1_h * p.c1_f);
  p.c0_f = circle.centre.imag() / ws;
  if (!(p.l1_h > 0) || !(p.c1_f > 0) || !(p.c0_f > 0) || !std::isfinite(p.r1_ohm))
    throw std::invalid_argument(
        "bvd_start_from_circle: the points do not trace a resonance circle");
  return p;
}

namespace {

struct Model {
  const Eigen::VectorXd& f;
  const Eigen::VectorXcd& z;
  const Eigen::VectorXd& sigma;
  const Eigen::VectorXcd& yb;
  Eigen::Index first, n;

  double scale(Eigen::Index k) const {  // per component
    return sigma.size() ? sigma[k] / std::sqrt(2.0) : std::abs(z[k]);
  }
  static BvdParams params(const Eigen::VectorXd& t) {
    return {std::exp(t[0]), std::exp(t[1]), std::exp(t[2]), std::exp(t[3])};
  }
  // Residuals (Z_model − Z)/scale as [Re; Im] per point, and the Jacobian in ln p.
  void eval(const Eigen::VectorXd& t, Eigen::VectorXd& r, Eigen::MatrixXd* jac) const {
    const BvdParams p = params(t);
    r.resize(2 * n);
    if (jac) jac->resize(2 * n, 4);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index k = first + i;
      const double w = kTwoPi * f[k];
      const cd s(0.0, w);
      const cd ym = numerics::reciprocal(p.r1_ohm + s * p.l1_h + numerics::reciprocal(s * p.c1_f));
      const cd y = s * p.c0_f + ym + (yb.size() ? yb[k] : cd(0.0));
      const cd zm = numerics::reciprocal(y);
      const double sc = scale(k);
      const cd e = (zm - z[k]) / sc;
      r[2 * i] = e.real();
      r[2 * i + 1] = e.imag();
      if (!jac) continue;
      const cd ym2 = ym * ym;
      const cd dy[4] = {-ym2 * p.r1_ohm, -ym2 * s * p.l1_h, numerics::divide(ym2, s * p.c1_f), s * p.c0_f};
      for (int j = 0; j < 4; ++j) {
        const cd dz = -zm * zm * dy[j] / sc;  // dZ = −Z² dY
        (*jac)(2 * i, j) = dz.real();
        (*jac)(2 * i + 1, j) = dz.imag();
      }
    }
  }
};

}  // namespace

BvdFit fit_bvd(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, const Eigen::VectorXd& z_sigma,
               const Eigen::VectorXcd& y_background, Eigen::Index first, Eigen::Index last,
               const BvdParams& start, const BvdFitOptions& opt) {
  check_range("fit_bvd", f, first, last);
  if (z.size() != f.size() || (z_sigma.size() && z_sigma.size() != f.size()) ||
      (y_background.size() && y_background.size() != f.size()))
    throw std::invalid_argument("fit_bvd: f, z, z_sigma and y_background sizes differ");
  if (!(start.r1_ohm > 0 && start.l1_h > 0 && start.c1_f > 0 && start.c0_f > 0))
    throw std::invalid_argument("fit_bvd: start values must be > 0");
  const Eigen::Index n = last - first + 1;
  if (z_sigma.size())
    for (Eigen::Index k = first; k <= last; ++k)
      if (!(z_sigma[k] > 0))
        throw std::invalid_argument("fit_bvd: z_sigma must be > 0 inside the window");
  const Model m{f, z, z_sigma, y_background, first, n};

  BvdFit out;
  out.points = static_cast<std::size_t>(n);
  out.weighted = z_sigma.size() > 0;
  Eigen::VectorXd t(4);
  t << std::log(start.r1_ohm), std::log(start.l1_h), std::log(start.c1_f), std::log(start.c0_f);
  numerics::LmProblem pb;
  pb.residual = [&](const Eigen::VectorXd& x) -> std::optional<Eigen::VectorXd> {
    Eigen::VectorXd r;
    m.eval(x, r, nullptr);
    return r;
  };
  pb.jacobian = [&](const Eigen::VectorXd& x, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const numerics::LmJacobianCall&) {
    Eigen::VectorXd r;
    m.eval(x, r, &j);
    return j.allFinite();
  };
  numerics::LmSettings ls;  // the damping of this fit before the shared engine (its figures were measured so)
  ls.max_iterations = opt.max_iterations;
  ls.max_tries = 40;
  ls.mu_down = 10;
  ls.mu_up = 10;
  ls.accept_equal = true;
  ls.step_tolerance = opt.step_tolerance;
  ls.tiny_rejected_step_converges = false;
  ls.on_stall = numerics::LmSettings::Stall::converged;  // no step lowers the cost even at μ → ∞: a minimum to rounding
  const numerics::LmRun run = numerics::levenberg_marquardt(pb, t, ls);
  if (run.stop == numerics::LmRun::Stop::bad_start)
    throw std::invalid_argument("fit_bvd: the start values give a non-finite impedance");
  out.iterations = run.iterations;
  out.converged = run.converged;
  if (!out.converged) out.message = "iteration limit reached";
  t = run.x;
  const Eigen::MatrixXd& jac = run.j;
  const double cost = 2.0 * run.cost;  // ‖r‖²
  out.p = Model::params(t);
  // Covariance (Jacobian at the solution): (JᵀJ)⁻¹ for whitened residuals; with
  // relative weights the scale of the noise is unknown and the residual sets it.
  const Eigen::Index dof = 2 * n - 4;
  Eigen::Matrix4d cov = numerics::lm_covariance(jac);
  if (out.weighted) {
    out.chi2_per_dof = dof > 0 ? cost / double(dof) : kNaN;
  } else {
    cov *= dof > 0 ? cost / double(dof) : kNaN;
  }
  out.cov_ln = cov;
  const double sd[4] = {std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2)),
                        std::sqrt(cov(3, 3))};
  out.sigma = {out.p.r1_ohm * sd[0], out.p.l1_h * sd[1], out.p.c1_f * sd[2], out.p.c0_f * sd[3]};
  double rel = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index k = first + i;
    const cd y = out.p.admittance(f[k]) + (y_background.size() ? y_background[k] : cd(0.0));
    rel += std::norm(numerics::divide(numerics::reciprocal(y) - z[k], z[k]));
  }
  out.rms_rel_residual = std::sqrt(rel / double(n));
  return out;
}

}  // namespace piezo::dsp
