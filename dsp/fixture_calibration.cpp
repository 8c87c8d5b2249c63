#include "dsp/fixture_calibration.hpp"

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "numerics/levenberg_marquardt.hpp"

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
enum P { kU, kBeta, kTau, kRho, kRs, kParams };

struct Point {
  int standard;      // 0 open, 1 short, 2 load
  double w;          // rad/s
  cd t;              // measured transfer
  double inv_sigma;  // 1/σ per real component
};

struct Model {
  double r1n;
  LoadStandard load;
  cd transfer(const Point& p, const std::array<double, kParams>& th) const {
    cd yb = 0.0;
    if (p.standard == 1) yb = 1.0 / th[kRs];
    if (p.standard == 2) yb = 1.0 / (th[kRs] + load.impedance(p.w / kTwoPi));
    return std::exp(cd(0.0, -p.w * th[kTau])) /
           (th[kU] + cd(0.0, p.w * th[kBeta]) + th[kRho] * r1n * yb);
  }
};
}  // namespace

FixtureCalibration fit_fixture(const CalibrationStandards& s) {
  const char* who = "fit_fixture";
  if (!s.open && !s.shrt && !s.load)
    throw std::invalid_argument(std::string(who) + ": no calibration standard");
  if (!(s.r1_nominal_ohm > 0))
    throw std::invalid_argument(std::string(who) + ": nominal R1 must be positive");
  if (s.load && !(s.load_value.ohm > 0))
    throw std::invalid_argument(std::string(who) + ": load value must be positive");
  const double r1 = s.r1_nominal_ohm;
  std::vector<Point> pts;
  auto add = [&](const std::optional<MeasuredStandard>& m, int id) {
    if (!m) return;
    if (m->f_hz.size() != m->z_ohm.size())
      throw std::invalid_argument(std::string(who) + ": f and Z differ in length");
    double tscale = 0;
    for (Eigen::Index k = 0; k < m->f_hz.size(); ++k)
      tscale += std::abs(m->z_ohm[k] / (m->z_ohm[k] + r1));
    tscale /= std::max<double>(1.0, double(m->f_hz.size()));
    for (Eigen::Index k = 0; k < m->f_hz.size(); ++k) {
      if (!(m->f_hz[k] > 0)) continue;
      const cd z = m->z_ohm[k];
      if (!std::isfinite(z.real()) || !std::isfinite(z.imag())) continue;
      const cd t = z / (z + r1);
      double sigma_t = 1e-3 * tscale;  // equal weights without σ
      if (m->z_sigma_ohm.size() == m->f_hz.size())
        sigma_t = r1 / std::norm(z + r1) * m->z_sigma_ohm[k] / std::sqrt(2.0);
      if (!(sigma_t > 0) || !std::isfinite(sigma_t)) continue;
      pts.push_back({id, kTwoPi * m->f_hz[k], t, 1.0 / sigma_t});
    }
  };
  add(s.open, 0);
  add(s.shrt, 1);
  add(s.load, 2);
  if (pts.size() < 8)
    throw std::invalid_argument(std::string(who) + ": fewer than 8 usable frequency points");
  const Model model{r1, s.load_value};

  FixtureCalibration out;
  std::array<bool, kParams> free{};
  free[kTau] = true;
  free[kU] = free[kBeta] = s.open.has_value();
  free[kRs] = s.shrt.has_value();
  free[kRho] = s.load.has_value();
  if (!s.open)
    out.assumptions.push_back(
        "no open standard: DAQ input and fixture capacitance taken as absent (u = 1, beta = 0)");
  if (!s.shrt && s.load)
    out.assumptions.push_back("no short standard: lead resistance taken as 0 in the R1 error");
  if (!s.load) out.assumptions.push_back("no load standard: R1 taken as nominal (rho = 1)");

  // Start values from the raw standards: 1/T_m ≈ u + jω(β + τ) + ρ·R1·Y_b.
  std::array<double, kParams> th{1.0, 0.0, s.skew_guess_s.value_or(0.0), 1.0, 0.0};
  if (s.shrt) {
    double acc = 0;
    int n = 0;
    for (const auto& p : pts)
      if (p.standard == 1) acc += (1.0 / p.t).real(), ++n;
    const double g = acc / n - 1.0;  // ≈ R1/Rs
    th[kRs] = g > 0 ? r1 / g : 1.0;
  }
  if (s.open) {
    double acc = 0;
    int n = 0;
    for (const auto& p : pts)
      if (p.standard == 0) acc += (1.0 / p.t).imag() / p.w, ++n;
    th[kBeta] = std::max(0.0, acc / n - th[kTau]);
  }
  // Natural scales of the parameters (for steps and conditioning).
  const double wmax = [&] {
    double w = 0;
    for (const auto& p : pts) w = std::max(w, p.w);
    return w;
  }();
  const std::array<double, kParams> scale{1.0, 1.0 / wmax, 1.0 / wmax, 1.0, std::max(1.0, th[kRs])};

  std::vector<int> idx;
  for (int i = 0; i < kParams; ++i)
    if (free[i]) idx.push_back(i);
  const auto np = static_cast<Eigen::Index>(idx.size());
  const auto nr = static_cast<Eigen::Index>(2 * pts.size());
  auto residual = [&](const std::array<double, kParams>& t) {
    Eigen::VectorXd r(nr);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const cd d = (pts[i].t - model.transfer(pts[i], t)) * pts[i].inv_sigma;
      r(static_cast<Eigen::Index>(2 * i)) = d.real();
      r(static_cast<Eigen::Index>(2 * i + 1)) = d.imag();
    }
    return r;
  };
  // The free parameters in units of their scales, from the start th0.
  const auto th0 = th;
  auto params = [&](const Eigen::VectorXd& u) {
    auto t = th0;
    for (Eigen::Index c = 0; c < np; ++c)
      t[idx[static_cast<std::size_t>(c)]] += u[c] * scale[idx[static_cast<std::size_t>(c)]];
    return t;
  };
  numerics::LmProblem pb;
  pb.residual = [&](const Eigen::VectorXd& u) -> std::optional<Eigen::VectorXd> {
    const auto t = params(u);
    if (t[kRs] < 0 || t[kRho] <= 0 || t[kU] <= 0) return std::nullopt;  // not a physical fixture
    return residual(t);
  };
  pb.jacobian = [&](const Eigen::VectorXd& u, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const numerics::LmJacobianCall&) {
    const auto t = params(u);
    j.resize(nr, np);
    for (Eigen::Index c = 0; c < np; ++c) {
      const int i = idx[static_cast<std::size_t>(c)];
      auto tp = t, tm = t;
      const double h = 1e-6 * scale[i];
      tp[i] += h;
      tm[i] -= h;
      j.col(c) =
          (residual(tp) - residual(tm)) / (2 * h) * scale[i];  // per unit of scaled parameter
    }
    return j.allFinite();
  };
  numerics::LmSettings ls;  // this fit's damping before the shared engine
  ls.max_iterations = 200;
  ls.max_tries = 20;
  ls.mu_down = 10;
  ls.mu_up = 10;
  ls.diag_floor = 1e-30;
  ls.relative_cost_tolerance = 1e-12;
  ls.tiny_rejected_step_converges = false;
  ls.on_stall = numerics::LmSettings::Stall::converged;  // no step lowers the cost: a minimum (to rounding)
  const numerics::LmRun run = numerics::levenberg_marquardt(pb, Eigen::VectorXd::Zero(np), ls);
  if (run.stop == numerics::LmRun::Stop::bad_start)
    throw std::invalid_argument("fit_fixture: the starting fixture model gives a non-finite transfer");
  out.iterations = run.iterations;
  out.converged = run.converged;
  th = params(run.x);
  const double cost = 2.0 * run.cost;  // ‖r‖²
  const Eigen::MatrixXd& jm = run.j;
  const double dof = std::max<double>(1.0, double(nr - np));
  out.chi2_reduced = cost / dof;
  // Covariance of the scaled free parameters, inflated by χ²_red when the model misfits.
  Eigen::MatrixXd cov = numerics::lm_covariance(jm) * std::max(1.0, out.chi2_reduced);
  std::array<double, kParams> sd{};
  for (Eigen::Index c = 0; c < np; ++c) {
    const int i = idx[static_cast<std::size_t>(c)];
    sd[i] = std::sqrt(std::max(0.0, cov(c, c))) * scale[i];
  }
  double rr = 0;
  for (const auto& p : pts) rr += std::norm((p.t - model.transfer(p, th)) / model.transfer(p, th));
  out.residual_rel_rms = std::sqrt(rr / double(pts.size()));

  out.skew_s = th[kTau];
  out.skew_sigma_s = sd[kTau];
  if (s.open) {
    out.fixture_capacitance_f = th[kBeta] / (th[kRho] * r1);
    // σ of β/(ρ·R1) term by term: as a relative σ times the value it read
    // 0 ± 5e275 F where β is near 0 (a fixture without parallel capacitance).
    out.fixture_capacitance_sigma_f =
        std::hypot(sd[kBeta] / (th[kRho] * r1), th[kBeta] * sd[kRho] / (th[kRho] * th[kRho] * r1));
    out.open_dc_transfer = 1.0 / th[kU];
    out.open_dc_transfer_sigma = sd[kU] / (th[kU] * th[kU]);
  }
  if (s.shrt) {
    out.lead_resistance_ohm = th[kRs];
    out.lead_resistance_sigma_ohm = sd[kRs];
  }
  if (s.load) {
    out.r1_error = th[kRho] - 1.0;
    out.r1_error_sigma = sd[kRho];
  }
  return out;
}

}  // namespace piezo::dsp
