#include "dsp/fixture_standards.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// (jx)^k = j^k·x^k: re/im parts of the basis function k at x = ω/ω_s.
cd basis(int k, double x) {
  static const cd jk[4] = {cd(1, 0), cd(0, 1), cd(-1, 0), cd(0, -1)};
  return jk[k % 4] * std::pow(x, k);
}
}  // namespace

cd StandardModel::impedance(double f) const {
  // Below the lowest bin the polynomial extends smoothly to DC; above the band it is unknown.
  if (!(f >= 0.0 && f <= 1.000001 * fmax_hz))
    throw std::invalid_argument("calibration standard evaluated at " + std::to_string(f) +
                                " Hz, above the band it was measured over (up to " +
                                std::to_string(fmax_hz) +
                                " Hz): measure the standards over the whole band of the estimate");
  const double x = kTwoPi * f / omega_scale;
  cd v = 0;
  for (Eigen::Index k = 0; k < c.size(); ++k) v += c[k] * basis(static_cast<int>(k), x);
  return admittance ? 1.0 / v : v;
}

double StandardModel::impedance_sigma(double f) const {
  const double x = kTwoPi * f / omega_scale;
  Eigen::VectorXd pr = Eigen::VectorXd::Zero(c.size()), pi = Eigen::VectorXd::Zero(c.size());
  cd v = 0;
  for (Eigen::Index k = 0; k < c.size(); ++k) {
    const cd b = basis(static_cast<int>(k), x);
    pr[k] = b.real();
    pi[k] = b.imag();
    v += c[k] * b;
  }
  const double var = pr.dot(cov * pr) + pi.dot(cov * pi);  // E|δX|²
  const double sx = std::sqrt(std::max(var, 0.0));
  return admittance ? sx / std::norm(v) : sx;  // δZ = −δY/Y²
}

StandardModel fit_standard(const MeasuredStandard& m, bool as_admittance, int degree,
                           const std::string& what) {
  const std::string who = "fit_standard (" + what + ")";
  if (degree < 1 || degree > 8) throw std::invalid_argument(who + ": degree must be 1..8");
  if (m.f_hz.size() != m.z_ohm.size() ||
      (m.z_sigma_ohm.size() && m.z_sigma_ohm.size() != m.f_hz.size()))
    throw std::invalid_argument(who + ": f, Z and sigma differ in length");
  std::vector<Eigen::Index> idx;
  for (Eigen::Index k = 0; k < m.f_hz.size(); ++k) {
    if (!(m.f_hz[k] > 0)) continue;
    if (!std::isfinite(m.z_ohm[k].real()) || !std::isfinite(m.z_ohm[k].imag()) || m.z_ohm[k] == 0.0)
      throw std::invalid_argument(who + ": impedance at " + std::to_string(m.f_hz[k]) +
                                  " Hz is not finite/non-zero");
    idx.push_back(k);
  }
  const auto n = static_cast<Eigen::Index>(idx.size());
  const int p = degree + 1;
  if (n < 2 * p)
    throw std::invalid_argument(who + ": " + std::to_string(n) + " frequency points for " +
                                std::to_string(p) + " coefficients (need at least " +
                                std::to_string(2 * p) + ")");
  StandardModel sm;
  sm.admittance = as_admittance;
  sm.fmin_hz = m.f_hz[idx.front()];
  sm.fmax_hz = m.f_hz[idx.back()];
  for (auto k : idx)
    sm.fmin_hz = std::min(sm.fmin_hz, m.f_hz[k]), sm.fmax_hz = std::max(sm.fmax_hz, m.f_hz[k]);
  sm.omega_scale = kTwoPi * sm.fmax_hz;
  // Rows: real and imaginary parts of every point, weighted by 1/σ of X.
  Eigen::MatrixXd a(2 * n, p);
  Eigen::VectorXd y(2 * n), w(n);
  std::vector<cd> xs(static_cast<std::size_t>(n));
  double xscale = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const cd z = m.z_ohm[idx[static_cast<std::size_t>(i)]];
    xs[static_cast<std::size_t>(i)] = as_admittance ? 1.0 / z : z;
    xscale += std::abs(xs[static_cast<std::size_t>(i)]);
  }
  xscale /= double(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto k = idx[static_cast<std::size_t>(i)];
    const cd x = xs[static_cast<std::size_t>(i)];
    double sigma;
    if (m.z_sigma_ohm.size()) {
      const double sz = m.z_sigma_ohm[k];
      sigma = as_admittance ? sz / std::norm(m.z_ohm[k]) : sz;  // δY = −δZ/Z²
      sigma /= std::sqrt(2.0);                                  // per real component
    } else {
      sigma = 1e-3 * std::max(std::abs(x), 1e-9 * xscale);  // relative weights
    }
    if (!(sigma > 0) || !std::isfinite(sigma))
      throw std::invalid_argument(who + ": non-positive sigma");
    w[i] = 1.0 / sigma;
    const double xf = kTwoPi * m.f_hz[k] / sm.omega_scale;
    for (int j = 0; j < p; ++j) {
      const cd b = basis(j, xf);
      a(2 * i, j) = b.real() * w[i];
      a(2 * i + 1, j) = b.imag() * w[i];
    }
    y(2 * i) = x.real() * w[i];
    y(2 * i + 1) = x.imag() * w[i];
  }
  // Column scaling for conditioning, then QR.
  Eigen::VectorXd cs = a.colwise().norm().transpose();
  for (int j = 0; j < p; ++j)
    if (!(cs[j] > 0))
      throw std::invalid_argument(who + ": degenerate fit (a basis function vanishes)");
  const Eigen::MatrixXd as = a * cs.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(as);
  if (qr.rank() < p)
    throw std::invalid_argument(who + ": degenerate fit (rank " + std::to_string(qr.rank()) + ")");
  sm.c = qr.solve(y).cwiseQuotient(cs);
  const Eigen::VectorXd r = a * sm.c - y;
  const double dof = double(2 * n - p);
  sm.chi2_reduced = r.squaredNorm() / dof;
  Eigen::MatrixXd ata_inv = (as.transpose() * as).inverse();
  ata_inv = cs.cwiseInverse().asDiagonal() * ata_inv * cs.cwiseInverse().asDiagonal();
  sm.cov = ata_inv * (m.z_sigma_ohm.size() ? std::max(1.0, sm.chi2_reduced) : sm.chi2_reduced);
  sm.points = static_cast<std::size_t>(n);
  double rr = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const double xf = kTwoPi * m.f_hz[idx[static_cast<std::size_t>(i)]] / sm.omega_scale;
    cd v = 0;
    for (int j = 0; j < p; ++j) v += sm.c[j] * basis(j, xf);
    rr += std::norm((xs[static_cast<std::size_t>(i)] - v) / v);
  }
  sm.residual_rel_rms = std::sqrt(rr / double(n));
  return sm;
}

}  // namespace piezo::dsp
