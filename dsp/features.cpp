#include "dsp/features.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

namespace piezo::dsp {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

double db(std::complex<double> z) { return 20.0 * std::log10(std::abs(z)); }

// Indices of prominent local minima (sign = +1) or maxima (sign = −1) of y.
std::vector<Eigen::Index> prominent_extrema(const Eigen::VectorXd& f, const Eigen::VectorXd& y,
                                            double sign, const FeatureOptions& opt) {
  std::vector<Eigen::Index> out;
  const Eigen::Index n = y.size();
  for (Eigen::Index i = 1; i + 1 < n; ++i) {
    const double v = sign * y[i];
    if (!(v < sign * y[i - 1] && v <= sign * y[i + 1])) continue;
    if (f[i] < opt.fmin_hz || f[i] > opt.fmax_hz) continue;
    const double reach = opt.search_rel * f[i];
    double left = v, right = v;
    bool left_ok = false, right_ok = false;
    for (Eigen::Index k = i - 1; k >= 0 && f[i] - f[k] <= reach; --k) {
      if (sign * y[k] < v) break;
      left = std::max(left, sign * y[k]);
      if (left - v >= opt.min_prominence_db) { left_ok = true; break; }
    }
    for (Eigen::Index k = i + 1; k < n && f[k] - f[i] <= reach; ++k) {
      if (sign * y[k] < v) break;
      right = std::max(right, sign * y[k]);
      if (right - v >= opt.min_prominence_db) { right_ok = true; break; }
    }
    if (left_ok && right_ok) out.push_back(i);
  }
  return out;
}

// Weighted quadratic fit of y over i ± h; vertex and its standard deviation.
Feature refine_quadratic(const Eigen::VectorXd& f, const Eigen::VectorXd& y,
                         const Eigen::VectorXd& sy, Eigen::Index i, int h) {
  const Eigen::Index a = std::max<Eigen::Index>(0, i - h), b = std::min<Eigen::Index>(f.size() - 1, i + h);
  const Eigen::Index m = b - a + 1;
  if (m < 3) return {f[i], kNaN};
  const double x0 = f[i], sc = (f[b] - f[a]) / 2.0;
  Eigen::MatrixXd X(m, 3);
  Eigen::VectorXd Y(m), W(m);
  const bool have_sigma = sy.size() == f.size();
  for (Eigen::Index k = 0; k < m; ++k) {
    const double x = (f[a + k] - x0) / sc;
    X.row(k) << 1.0, x, x * x;
    Y[k] = y[a + k];
    W[k] = have_sigma && sy[a + k] > 0 ? 1.0 / sy[a + k] : 1.0;
  }
  const Eigen::MatrixXd Xw = W.asDiagonal() * X;
  const Eigen::VectorXd Yw = W.asDiagonal() * Y;
  const Eigen::MatrixXd N = Xw.transpose() * Xw;
  const Eigen::Vector3d c = N.ldlt().solve(Xw.transpose() * Yw);
  if (c[2] == 0.0) return {f[i], kNaN};
  const double xv = -c[1] / (2.0 * c[2]);
  if (std::abs(xv) > 1.0) return {f[i], kNaN};  // vertex outside the fitted span
  Eigen::Matrix3d cov = N.inverse();
  if (!have_sigma) {  // scale by the residual variance
    const double dof = double(m - 3);
    const double s2 = dof > 0 ? (Yw - Xw * c).squaredNorm() / dof : kNaN;
    cov *= s2;
  }
  const Eigen::Vector3d J(0.0, -1.0 / (2.0 * c[2]), c[1] / (2.0 * c[2] * c[2]));
  return {x0 + xv * sc, std::sqrt(std::max(0.0, J.dot(cov * J))) * sc};
}

// Im(1/Z) = ω(C + Dω²) by weighted least squares over [lo, hi].
void fit_capacitance(const Eigen::VectorXd& f, const Eigen::VectorXcd& z, const Eigen::VectorXd& zs,
                     double lo, double hi, ImpedanceFeatures& out) {
  std::vector<Eigen::Index> idx;
  for (Eigen::Index k = 0; k < f.size(); ++k)
    if (f[k] > 0 && f[k] >= lo && f[k] <= hi && std::abs(z[k]) > 0) idx.push_back(k);
  if (idx.size() < 3) return;
  const auto m = static_cast<Eigen::Index>(idx.size());
  const bool have_sigma = zs.size() == f.size();
  const double wref = kTwoPi * hi;
  Eigen::MatrixXd X(m, 2);
  Eigen::VectorXd Y(m), W(m);
  for (Eigen::Index r = 0; r < m; ++r) {
    const Eigen::Index k = idx[static_cast<std::size_t>(r)];
    const double w = kTwoPi * f[k];
    const double az = std::abs(z[k]);
    X.row(r) << w, w * std::pow(w / wref, 2);
    Y[r] = (1.0 / z[k]).imag();
    const double sy = have_sigma ? zs[k] / (az * az) : 0.0;  // |δ(1/Z)| = |δZ|/|Z|²
    W[r] = sy > 0 ? std::sqrt(2.0) / sy : 1.0;  // Im part carries half of E|δY|²
  }
  const Eigen::MatrixXd Xw = W.asDiagonal() * X;
  const Eigen::VectorXd Yw = W.asDiagonal() * Y;
  const Eigen::Matrix2d N = Xw.transpose() * Xw;
  const Eigen::Vector2d c = N.ldlt().solve(Xw.transpose() * Yw);
  Eigen::Matrix2d cov = N.inverse();
  if (!have_sigma) cov *= m > 2 ? (Yw - Xw * c).squaredNorm() / double(m - 2) : kNaN;
  out.capacitance_f = c[0];
  out.capacitance_sigma_f = std::sqrt(std::max(0.0, cov(0, 0)));
}

void capacitance_band(const Eigen::VectorXd& f, const ImpedanceFeatures& ft, const FeatureOptions& o,
                      double& lo, double& hi) {
  lo = o.cap_f_lo_hz;
  hi = o.cap_f_hi_hz;
  if (lo <= 0) {
    lo = std::max(o.fmin_hz, 0.0);
    for (Eigen::Index k = 0; k < f.size(); ++k)
      if (f[k] > 0) { lo = std::max(lo, f[k]); break; }
  }
  if (hi <= 0) {
    const double top = ft.resonances.empty() ? std::min(o.fmax_hz, f[f.size() - 1])
                                             : ft.resonances.front().f_hz;
    hi = o.cap_rel_hi * top;
  }
}

}  // namespace

ImpedanceFeatures find_features(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                                const Eigen::VectorXd& zs, const FeatureOptions& opt) {
  if (f.size() != z.size() || f.size() < 5)
    throw std::invalid_argument("find_features: need >= 5 points and equal sizes");
  if (zs.size() != 0 && zs.size() != f.size())
    throw std::invalid_argument("find_features: z_sigma size differs");
  Eigen::VectorXd y(f.size()), sy;
  for (Eigen::Index k = 0; k < f.size(); ++k) y[k] = db(z[k]);
  if (zs.size()) {
    sy.resize(f.size());
    // σ of 20·log10|Z|: the radial part of δZ carries half of E|δZ|².
    for (Eigen::Index k = 0; k < f.size(); ++k)
      sy[k] = 20.0 / std::log(10.0) * zs[k] / std::sqrt(2.0) / std::abs(z[k]);
  }
  ImpedanceFeatures out;
  for (Eigen::Index i : prominent_extrema(f, y, +1.0, opt))
    out.resonances.push_back(refine_quadratic(f, y, sy, i, opt.fit_points));
  for (Eigen::Index i : prominent_extrema(f, y, -1.0, opt))
    out.antiresonances.push_back(refine_quadratic(f, y, sy, i, opt.fit_points));
  for (auto* list : {&out.resonances, &out.antiresonances})
    for (auto& ft : *list) ft.extremum_hz = ft.f_hz;
  double lo, hi;
  capacitance_band(f, out, opt, lo, hi);
  fit_capacitance(f, z, zs, lo, hi, out);
  return out;
}

ImpedanceFeatures find_features(const std::function<std::complex<double>(double)>& zf,
                                double fmin, double fmax, double step, const FeatureOptions& opt) {
  if (!(step > 0) || !(fmax > fmin) || fmin < 0)
    throw std::invalid_argument("find_features: need 0 <= fmin < fmax and step > 0");
  const auto n = static_cast<Eigen::Index>(std::floor((fmax - fmin) / step)) + 1;
  if (n < 5) throw std::invalid_argument("find_features: band holds fewer than 5 steps");
  Eigen::VectorXd f(n), y(n);
  Eigen::VectorXcd z(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    f[k] = fmin + step * double(k);
    z[k] = zf(f[k]);
    y[k] = db(z[k]);
  }
  auto golden = [&](double a, double b, double sign) {
    const double g = (std::sqrt(5.0) - 1.0) / 2.0;
    double c = b - g * (b - a), d = a + g * (b - a);
    double fc = sign * db(zf(c)), fd = sign * db(zf(d));
    while (b - a > 1e-10 * std::max(1.0, std::abs(b))) {
      if (fc < fd) { b = d; d = c; fd = fc; c = b - g * (b - a); fc = sign * db(zf(c)); }
      else { a = c; c = d; fc = fd; d = a + g * (b - a); fd = sign * db(zf(d)); }
    }
    return 0.5 * (a + b);
  };
  ImpedanceFeatures out;
  for (Eigen::Index i : prominent_extrema(f, y, +1.0, opt))
    out.resonances.push_back({golden(f[i - 1], f[i + 1], +1.0), kNaN});
  for (Eigen::Index i : prominent_extrema(f, y, -1.0, opt))
    out.antiresonances.push_back({golden(f[i - 1], f[i + 1], -1.0), kNaN});
  for (auto* list : {&out.resonances, &out.antiresonances})
    for (auto& ft : *list) ft.extremum_hz = ft.f_hz;
  double lo, hi;
  capacitance_band(f, out, opt, lo, hi);
  fit_capacitance(f, z, Eigen::VectorXd(), lo, hi, out);
  out.capacitance_sigma_f = kNaN;
  return out;
}

}  // namespace piezo::dsp
