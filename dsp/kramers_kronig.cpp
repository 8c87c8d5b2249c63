#include "dsp/kramers_kronig.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "dsp/features.hpp"
#include "dsp/vector_fitting.hpp"

namespace piezo::dsp {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

// At most `m` indices of z's grid, both ends included, spaced evenly in
// s_k = Σ|ln z_{j+1} − ln z_j| + (k/(n−1))·Σ|Δ ln z|: half of the points follow
// the turning of Z (resonances get dense points), half are even in index, so a
// smooth stretch keeps its share. All of them when n ≤ m.
std::vector<Eigen::Index> thin_grid(const Eigen::VectorXcd& z, int m) {
  const Eigen::Index n = z.size();
  std::vector<Eigen::Index> pick;
  if (n <= m) {
    pick.resize(static_cast<std::size_t>(n));
    for (Eigen::Index k = 0; k < n; ++k) pick[static_cast<std::size_t>(k)] = k;
    return pick;
  }
  std::vector<double> arc(static_cast<std::size_t>(n), 0.0);
  for (Eigen::Index k = 1; k < n; ++k)
    arc[k] = arc[k - 1] + std::abs(std::log(z[k] / z[k - 1]));  // principal log: |Δln|Z|| and Δphase
  const double total_turn = arc[n - 1];
  for (Eigen::Index k = 0; k < n; ++k)
    arc[k] += (total_turn > 0 ? total_turn : 1.0) * double(k) / double(n - 1);
  const double total = arc[n - 1];
  pick.push_back(0);
  Eigen::Index k = 0;
  for (int i = 1; i < m - 1; ++i) {
    const double target = total * double(i) / double(m - 1);
    while (k < n - 1 && arc[k] < target) ++k;
    if (k > pick.back() && k < n - 1) pick.push_back(k);
  }
  pick.push_back(n - 1);
  return pick;
}
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

  // The thinned grid the models are fitted on (see the header: arc length of ln Z).
  const std::vector<Eigen::Index> pick = thin_grid(z, std::max(16, opt.max_fit_points));
  const Eigen::Index m = static_cast<Eigen::Index>(pick.size());
  r.fit_points = static_cast<int>(m);
  Eigen::VectorXd fm(m);
  Eigen::VectorXcd zm(m);
  for (Eigen::Index i = 0; i < m; ++i) fm[i] = f[pick[i]], zm[i] = z[pick[i]];

  int pairs = opt.pole_pairs;
  if (pairs <= 0) {
    FeatureOptions fo;
    const auto ft = find_features(fm, zm, Eigen::VectorXd(), fo);
    pairs = std::max<int>(4, 2 + static_cast<int>(ft.resonances.size() + ft.antiresonances.size()));
  }
  pairs = std::min<int>({pairs, std::max(1, opt.max_pole_pairs), static_cast<int>(m / 4)});
  r.pole_pairs = pairs;
  VectorFitOptions vo;
  vo.pole_pairs = pairs;
  vo.iterations = opt.iterations;
  vo.max_pole_ratio = opt.max_pole_ratio;

  // Z form, fitted as s·Z; Y form as is. Weights: 1/σ of the fitted quantity, else relative;
  // a fitted point stands for the points of the full grid nearest to it (√count).
  Eigen::VectorXcd hz(m), hy(m);
  Eigen::VectorXd wz, wy;
  if (sigma.size()) {
    wz.resize(m);
    wy.resize(m);
  }
  for (Eigen::Index i = 0; i < m; ++i) {
    const Eigen::Index k = pick[i];
    const cd s(0.0, kTwoPi * f[k]);
    hz[i] = s * z[k];
    hy[i] = 1.0 / z[k];
    if (sigma.size()) {
      const Eigen::Index lo = i == 0 ? 0 : (pick[i - 1] + k + 1) / 2;
      const Eigen::Index hi = i + 1 == m ? n : (k + pick[i + 1] + 1) / 2;
      const double represented = std::sqrt(static_cast<double>(std::max<Eigen::Index>(1, hi - lo)));
      const double sr =
          std::max(sigma[k], 1e-6 * std::abs(z[k]));  // a zero σ must not make one point absolute
      wz[i] = represented / (std::abs(s) * sr);
      wy[i] = represented * std::norm(z[k]) / sr;
    }
  }
  const VectorFit fz = vector_fit(fm, hz, wz, vo);
  const VectorFit fy = vector_fit(fm, hy, wy, vo);
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
    const cd hzk = s * z[k], hyk = 1.0 / z[k];
    r.residual_z[k] = std::abs(fz.eval(s) - hzk) / std::abs(hzk);
    r.residual_y[k] = std::abs(fy.eval(s) - hyk) / std::abs(hyk);
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
  char buf[400];
  std::snprintf(
      buf, sizeof buf,
      "causality: rms residual Z %.3g, Y %.3g against %.3g (%d pole pairs, fitted on %d of %d points)%s; passivity: max -Re "
      "Z/|Z| %.3g "
      "at %.4g Hz%s",
      r.rms_residual_z, r.rms_residual_y, r.threshold, pairs, r.fit_points, static_cast<int>(n),
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
