#include "dsp/kramers_kronig.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

#include "dsp/features.hpp"
#include "dsp/vector_fitting.hpp"

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
}  // namespace

KramersKronigResult kramers_kronig_check(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                                         const Eigen::VectorXd& sigma,
                                         const KramersKronigOptions& opt) {
  const char* who = "kramers_kronig_check";
  const Eigen::Index n = f.size();
  if (z.size() != n || (sigma.size() && sigma.size() != n))
    throw std::invalid_argument(std::string(who) + ": f, Z and sigma differ in length");
  if (n < 16) throw std::invalid_argument(std::string(who) + ": need at least 16 frequencies");
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!(f[k] > 0))
      throw std::invalid_argument(std::string(who) + ": frequencies must be positive");
    if (!std::isfinite(z[k].real()) || !std::isfinite(z[k].imag()) || z[k] == 0.0)
      throw std::invalid_argument(std::string(who) + ": Z at " + std::to_string(f[k]) +
                                  " Hz is not finite/non-zero");
  }
  KramersKronigResult r;
  r.f_hz = f;
  int pairs = opt.pole_pairs;
  if (pairs <= 0) {
    FeatureOptions fo;
    const auto ft = find_features(f, z, Eigen::VectorXd(), fo);
    pairs = std::max<int>(4, 2 + static_cast<int>(ft.resonances.size() + ft.antiresonances.size()));
  }
  pairs = std::min<int>(pairs, static_cast<int>(n / 4));
  r.pole_pairs = pairs;
  VectorFitOptions vo;
  vo.pole_pairs = pairs;
  vo.iterations = opt.iterations;
  vo.max_pole_ratio = opt.max_pole_ratio;

  // Z form, fitted as s·Z; Y form as is. Weights: 1/σ of the fitted quantity, else relative.
  Eigen::VectorXcd hz(n), hy(n);
  Eigen::VectorXd wz, wy;
  if (sigma.size()) {
    wz.resize(n);
    wy.resize(n);
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd s(0.0, kTwoPi * f[k]);
    hz[k] = s * z[k];
    hy[k] = 1.0 / z[k];
    if (sigma.size()) {
      const double sr =
          std::max(sigma[k], 1e-6 * std::abs(z[k]));  // a zero σ must not make one point absolute
      wz[k] = 1.0 / (std::abs(s) * sr);
      wy[k] = std::norm(z[k]) / sr;
    }
  }
  const VectorFit fz = vector_fit(f, hz, wz, vo);
  const VectorFit fy = vector_fit(f, hy, wy, vo);
  r.residual_z.resize(n);
  r.residual_y.resize(n);
  r.residual.resize(n);
  r.passivity.resize(n);
  double sz = 0, sy = 0, s2 = 0, snoise = 0;
  for (Eigen::Index k = 0; k < n; ++k)
    if (sigma.size()) snoise += std::pow(sigma[k] / std::abs(z[k]), 2);
  r.threshold = opt.threshold_rel;
  if (sigma.size())
    r.threshold = std::max(r.threshold, opt.noise_factor * std::sqrt(snoise / double(n)));
  r.passive = true;
  for (Eigen::Index k = 0; k < n; ++k) {
    const cd s(0.0, kTwoPi * f[k]);
    r.residual_z[k] = std::abs(fz.eval(s) - hz[k]) / std::abs(hz[k]);
    r.residual_y[k] = std::abs(fy.eval(s) - hy[k]) / std::abs(hy[k]);
    r.passivity[k] = std::max(0.0, -z[k].real()) / std::abs(z[k]);
    const double local =
        r.threshold + (sigma.size() ? opt.noise_factor * sigma[k] / std::abs(z[k]) : 0.0);
    if (r.passivity[k] > local) r.passive = false;
    if (r.passivity[k] > r.max_passivity)
      r.max_passivity = r.passivity[k], r.max_passivity_f_hz = f[k];
    r.residual[k] = std::max({r.residual_z[k], r.residual_y[k], r.passivity[k]});
    sz += r.residual_z[k] * r.residual_z[k];
    sy += r.residual_y[k] * r.residual_y[k];
    s2 += r.residual[k] * r.residual[k];
    if (r.residual[k] > r.max_residual) r.max_residual = r.residual[k], r.max_residual_f_hz = f[k];
  }
  r.rms_residual_z = std::sqrt(sz / double(n));
  r.rms_residual_y = std::sqrt(sy / double(n));
  r.rms_residual = std::sqrt(s2 / double(n));
  r.causal = r.rms_residual_z <= r.threshold && r.rms_residual_y <= r.threshold;
  r.pass = r.causal && r.passive;
  char buf[320];
  std::snprintf(
      buf, sizeof buf,
      "causality: rms residual Z %.3g, Y %.3g against %.3g (%d pole pairs)%s; passivity: max -Re "
      "Z/|Z| %.3g "
      "at %.4g Hz%s",
      r.rms_residual_z, r.rms_residual_y, r.threshold, pairs,
      r.causal ? ""
               : (r.rms_residual_z > r.threshold ? " - Z is not causal/linear"
                                                 : " - Y = 1/Z is not causal/linear"),
      r.max_passivity, r.max_passivity_f_hz,
      r.passive
          ? ""
          : " - Z looks active (negative resistance): a late channel 2, or a wrong deskew sign?");
  r.note = buf;
  return r;
}

}  // namespace piezo::dsp
