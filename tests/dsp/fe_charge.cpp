#include "fe_charge.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>

#include "dsp/features.hpp"
#include "model/transient.hpp"

namespace piezo::fe5 {

namespace {
using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr std::size_t kRecord = 50000;  // 5 ms at 10 MS/s (the seed's duration)

// d ln|Z(jω)|/dω for Z = V/(sQ): Re(j·(V'/V − 1/s − Q'/Q)) at s = jω.
double dlnz(const std::vector<cd>& poles, const std::vector<cd>& res, double pole_v, double w) {
  const cd s(0.0, w);
  cd q = 0, dq = 0;
  for (std::size_t i = 0; i < poles.size(); ++i) {
    const bool pair = poles[i].imag() > 0;
    for (int c = 0; c < (pair ? 2 : 1); ++c) {
      const cd l = c ? std::conj(poles[i]) : poles[i], r = c ? std::conj(res[i]) : res[i];
      q += r / (s - l);
      dq -= r / ((s - l) * (s - l));
    }
  }
  const cd dl = -1.0 / (s - pole_v) - 1.0 / s - dq / q;
  return (cd(0, 1) * dl).real();
}

// The extremum next to f0 (Newton with a numerical second derivative).
double extremum_hz(const std::vector<cd>& poles, const std::vector<cd>& res, double pole_v, double f0) {
  double w = kTwoPi * f0;
  for (int it = 0; it < 60; ++it) {
    const double h = 1e-7 * w;
    const double g = dlnz(poles, res, pole_v, w);
    const double gp = (dlnz(poles, res, pole_v, w + h) - dlnz(poles, res, pole_v, w - h)) / (2 * h);
    const double step = g / gp;
    w -= step;
    if (std::abs(step) < 1e-13 * w) break;
  }
  return w / kTwoPi;
}
}  // namespace

std::complex<double> ChargeData::z(double f_hz) const {
  const double w = kTwoPi * f_hz;
  return 1.0 / (cd(0.0, w) * fe->port.charge_per_volt(w, damping));
}

double ChargeData::q_exact(double t) const {
  double acc = 0;
  for (std::size_t i = 0; i < poles.size(); ++i) {
    const cd term = residues[i] * std::exp(poles[i] * t);
    acc += poles[i].imag() > 0 ? 2.0 * term.real() : term.real();
  }
  return acc;
}

ChargeData charge_data(const FeChapter5& fe, double beta) {
  ChargeData d;
  d.fe = &fe;
  d.damping = {0.0, beta};
  std::vector<double> v(kRecord);
  for (std::size_t k = 0; k < kRecord; ++k)
    v[k] = d.drive.amplitude_v * std::exp(d.drive.pole_per_s * double(k) / d.sample_rate_hz);
  d.q = model::simulate_charge(fe.port, d.damping, v, d.sample_rate_hz);
  // Pole–residue form (eq. 114 of the exact response).
  const auto& p = fe.port;
  const double lv = d.drive.pole_per_s, a = d.drive.amplitude_v;
  cd c_at_lv = p.c_clamped + p.c_residual;
  for (const auto& m : p.modes) {
    if (!(m.omega > 0)) continue;
    const double c = d.damping.alpha + d.damping.beta * m.kappa;
    c_at_lv += m.participation * m.participation / (lv * lv + c * lv + m.omega * m.omega);
    if (m.participation == 0.0) continue;
    const cd lam(-c / 2, std::sqrt(m.omega * m.omega - c * c / 4));
    d.poles.push_back(lam);
    d.residues.push_back(a / (lam - lv) * m.participation * m.participation / (lam - std::conj(lam)));
  }
  d.poles.insert(d.poles.begin(), cd(lv, 0));
  d.residues.insert(d.residues.begin(), a * c_at_lv);
  return d;
}

double charge_noise_std(const ChargeData& d, double level) { return level * bvd::std_dev(d.q); }

std::vector<double> noisy_charge(const ChargeData& d, double level, std::uint64_t seed, std::size_t n) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd(0.0, charge_noise_std(d, level));
  std::vector<double> out(d.q.begin(), d.q.begin() + static_cast<std::ptrdiff_t>(n));
  for (double& x : out) x += nd(rng);
  return out;
}

study::StudyInput charge_study_input(const ChargeData& d) {
  study::StudyInput in;
  in.sample_rate_hz = d.sample_rate_hz;
  in.z_true = [&d](double f) { return d.z(f); };
  const auto truth = dsp::find_features(in.z_true, in.f_lo_hz, in.f_hi_hz, 10.0);
  for (const auto& f : truth.resonances) in.true_resonances_hz.push_back(f.f_hz);
  for (const auto& f : truth.antiresonances) in.true_antiresonances_hz.push_back(f.f_hz);
  return in;
}

FeatureBounds charge_feature_crb(const ChargeData& d, const study::StudyInput& in, double level,
                                 std::size_t n, double f_max_hz, std::size_t pairs) {
  // Free components: the drive pole and the strongest `pairs` pairs below f_max_hz.
  std::vector<std::size_t> osc;
  for (std::size_t i = 1; i < d.poles.size(); ++i)
    if (std::abs(d.poles[i]) <= kTwoPi * f_max_hz) osc.push_back(i);
  std::sort(osc.begin(), osc.end(), [&](std::size_t a, std::size_t b) {
    return std::abs(d.residues[a]) > std::abs(d.residues[b]);
  });
  osc.resize(std::min(pairs, osc.size()));
  std::vector<std::size_t> free{0};
  free.insert(free.end(), osc.begin(), osc.end());
  // θ: per free component (Re λ[, Im λ], Re r[, Im r]).
  std::vector<Eigen::Index> at;
  Eigen::Index np = 0;
  for (std::size_t i : free) {
    at.push_back(np);
    np += d.poles[i].imag() > 0 ? 4 : 2;
  }
  const double sigma = charge_noise_std(d, level);
  Eigen::MatrixXd fisher = Eigen::MatrixXd::Zero(np, np);
  Eigen::VectorXd g(np);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = double(k) / d.sample_rate_hz;
    for (std::size_t j = 0; j < free.size(); ++j) {
      const cd l = d.poles[free[j]], r = d.residues[free[j]], e = std::exp(l * t);
      const Eigen::Index a = at[j];
      if (l.imag() > 0) {
        g[a] = 2.0 * (r * t * e).real();
        g[a + 1] = 2.0 * (cd(0, 1) * r * t * e).real();
        g[a + 2] = 2.0 * e.real();
        g[a + 3] = 2.0 * (cd(0, 1) * e).real();
      } else {
        g[a] = (r * t * e).real();
        g[a + 1] = e.real();
      }
    }
    fisher += g * g.transpose() / (sigma * sigma);
  }
  const Eigen::VectorXd sc = fisher.diagonal().cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd cov =
      sc.asDiagonal() * (sc.asDiagonal() * fisher * sc.asDiagonal()).inverse() * sc.asDiagonal();

  // ∂f*/∂θ = −(∂h/∂θ)/(∂h/∂ω)/2π, h = d ln|Z|/dω (implicit-function theorem).
  auto bound = [&](double f_true) {
    const double fs = extremum_hz(d.poles, d.residues, d.drive.pole_per_s, f_true);
    const double w = kTwoPi * fs, hw = 1e-7 * w;
    const double dhdw = (dlnz(d.poles, d.residues, d.drive.pole_per_s, w + hw) -
                         dlnz(d.poles, d.residues, d.drive.pole_per_s, w - hw)) / (2 * hw);
    Eigen::VectorXd grad(np);
    for (std::size_t j = 0; j < free.size(); ++j) {
      const std::size_t i = free[j];
      const int m = d.poles[i].imag() > 0 ? 4 : 2;
      for (int c = 0; c < m; ++c) {
        auto poles = d.poles;
        auto res = d.residues;
        const bool pole_part = d.poles[i].imag() > 0 ? c < 2 : c < 1;
        cd& x = pole_part ? poles[i] : res[i];
        const bool imag = d.poles[i].imag() > 0 ? (c % 2 == 1) : false;
        const double h = 1e-6 * std::max(std::abs(x), 1e-300);
        const cd dx = imag ? cd(0, h) : cd(h, 0);
        x += dx;
        const double up = dlnz(poles, res, d.drive.pole_per_s, w);
        x -= 2.0 * dx;
        const double dn = dlnz(poles, res, d.drive.pole_per_s, w);
        grad[at[j] + c] = -((up - dn) / (2 * h)) / dhdw / kTwoPi;
      }
    }
    return std::sqrt(grad.dot(cov * grad)) / fs;
  };
  FeatureBounds b;
  for (double f : in.true_resonances_hz) b.res_rel.push_back(bound(f));
  for (double f : in.true_antiresonances_hz) b.anti_rel.push_back(bound(f));
  return b;
}

}  // namespace piezo::fe5
