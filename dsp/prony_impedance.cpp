#include "dsp/prony_impedance.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

namespace piezo::dsp {

namespace {
constexpr double kTwoPi = 2.0 * std::numbers::pi;

Eigen::MatrixXd stack(const DividerSignals& s) {
  Eigen::MatrixXd y(s.size(), 3);
  y.col(0) = s.v1;
  y.col(1) = s.v2;
  y.col(2) = s.i;
  return y;
}

// Matches each reference frequency with the nearest of `found` within ±2 %.
void accumulate(const std::vector<Feature>& ref, const std::vector<Feature>& found,
                std::vector<std::vector<double>>& acc) {
  for (std::size_t r = 0; r < ref.size(); ++r) {
    double best = kNaN, dist = 0.02 * ref[r].f_hz;
    for (const auto& f : found)
      if (std::abs(f.f_hz - ref[r].f_hz) < dist) {
        dist = std::abs(f.f_hz - ref[r].f_hz);
        best = f.f_hz;
      }
    if (std::isfinite(best)) acc[r].push_back(best);
  }
}

double stddev(const std::vector<double>& v) {
  if (v.size() < 2) return kNaN;
  double m = 0, s = 0;
  for (double x : v) m += x;
  m /= double(v.size());
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / double(v.size() - 1));
}
}  // namespace

void attach_direct_residual(PronyImpedance& m, const Eigen::MatrixXd& y, Eigen::Index n) {
  if (n <= 0) {
    m.direct_residual.resize(0, 3);
    return;
  }
  m.direct_residual = y.topRows(n) - reconstruct(m.fit, n);
}

std::complex<double> PronyImpedance::transform(Eigen::Index k, std::complex<double> s) const {
  std::complex<double> l = laplace(fit, k, s);
  if (onset_dt_s > 0) {
    // ∫_{−Δt}^0 v0 (1 + t/Δt) e^{−st} dt = v0 Δt (e^a − 1 − a)/a², a = sΔt
    const std::complex<double> a = s * onset_dt_s;
    const std::complex<double> g =
        std::abs(a) < 1e-3 ? 0.5 + a / 6.0 + a * a / 24.0 : (std::exp(a) - 1.0 - a) / (a * a);
    l += onset_v[static_cast<std::size_t>(k)] * onset_dt_s * g;
  }
  if (const Eigen::Index n = direct_residual.rows(); n > 0) {
    // ∫ r(t) e^{−st} dt for r linear between r_k at t_k = kΔt, from r_0 at t = 0
    // (the onset ramp covers t < 0) to 0 at t_n (the pole model holds from
    // there): hat functions, the first one halved. Horner in e^{−sΔt}.
    const double dt = fit.dt;
    const std::complex<double> a = s * dt, e = std::exp(-a);
    const bool small = std::abs(a) < 1e-3;
    const std::complex<double> hat = small ? 1.0 + a * a / 12.0 : (1.0 / e - 2.0 + e) / (a * a);
    const std::complex<double> half = small ? 0.5 - a / 6.0 + a * a / 24.0 : (a - 1.0 + e) / (a * a);
    // acc = acc·e + r_j written out on (re, im): std::complex's product
    // carries a NaN branch per step; for finite parts its value is this one.
    double acc_re = 0.0, acc_im = 0.0;
    const double e_re = e.real(), e_im = e.imag();
    for (Eigen::Index j = n - 1; j >= 1; --j) {
      const double re = acc_re * e_re - acc_im * e_im + direct_residual(j, k);
      acc_im = acc_re * e_im + acc_im * e_re;
      acc_re = re;
    }
    const std::complex<double> acc(acc_re, acc_im);
    l += dt * (direct_residual(0, k) * half + hat * e * acc);
  }
  return l;
}

std::complex<double> PronyImpedance::z(double f_hz) const {
  const std::complex<double> s(0.0, kTwoPi * f_hz);
  const std::complex<double> v2 = transform(1, s);
  return r1_ohm * v2 / (transform(0, s) - v2);
}

std::complex<double> PronyImpedance::zero_or_pole(double f_hz, bool resonance) const {
  // Newton on Z(s) = V2/I (resonance) or on 1/Z(s) (anti-resonance): V2 and I
  // share the divider's poles, which sit next to the anti-resonances when R1
  // is large; in the ratio they cancel, so the iteration sees a smooth function.
  auto g = [&](std::complex<double> s) {
    const std::complex<double> v2 = transform(1, s), i = transform(2, s);
    return resonance ? v2 / i : i / v2;
  };
  const double scale = kTwoPi * f_hz;
  // Damped Newton (a step is halved until |g| decreases), from several starts
  // around the extremum: with two close modes plain Newton jumps to the wrong
  // root. The root kept is the one nearest to the extremum within ±5 %.
  std::complex<double> best(kNaN, kNaN);
  double best_dist = 0.05 * scale;
  for (double zeta0 : {0.0, 0.005, 0.01, 0.02, 0.04}) {
    std::complex<double> x(-zeta0 * scale, scale);
    double gx = std::abs(g(x));
    bool converged = false;
    for (int it = 0; it < 60 && std::isfinite(gx); ++it) {
      const std::complex<double> h(1e-6 * scale, 0.0);
      const std::complex<double> d = (g(x + h) - g(x - h)) / (2.0 * h);
      if (d == 0.0) break;
      std::complex<double> step = g(x) / d;
      if (std::abs(step) > 0.02 * scale) step *= 0.02 * scale / std::abs(step);  // trust region
      double gn = std::abs(g(x - step));
      int halvings = 0;
      while (!(gn < gx) && halvings < 30) {
        step *= 0.5;
        gn = std::abs(g(x - step));
        ++halvings;
      }
      if (!(gn < gx) && std::abs(step) > 1e-9 * scale) break;  // stuck
      x -= step;
      gx = gn;
      // g sums terms that cancel at its zero, so rounding bounds the attainable step.
      if (std::abs(step) < 1e-10 * scale) {
        converged = true;
        break;
      }
    }
    if (!converged) continue;
    const double dist = std::abs(std::abs(x) - scale);
    if (x.real() < 0 && dist < best_dist) {
      best = x;
      best_dist = dist;
    }
  }
  return best;
}

void refine_features_to_modal(const PronyImpedance& m, ImpedanceFeatures& f) {
  auto refine = [&](std::vector<Feature>& list, bool resonance) {
    for (auto& ft : list) {
      ft.extremum_hz = ft.f_hz;
      const auto s = m.zero_or_pole(ft.f_hz, resonance);
      if (std::isfinite(s.real()) && s.real() < 0) {
        ft.f_hz = std::abs(s) / kTwoPi;
        ft.damping_ratio = -s.real() / std::abs(s);
      }
    }
  };
  refine(f.resonances, true);
  refine(f.antiresonances, false);
}

namespace {

// What fit_prony_impedance fits: the divider's v1, v2, i stacked, with the
// Prony options completed (noise model, skipped direct samples).
struct PronyProblem {
  DividerSignals s;
  Eigen::MatrixXd y;
  PronyOptions po;
  Eigen::Index direct = 0;
};

PronyProblem prony_problem(const DividerRecord& rec, const PronyImpedanceOptions& opt,
                           bool automatic) {
  PronyProblem p{prepare_divider(rec, "impedance_prony", opt.prep), {}, opt.prony, 0};
  const DividerSignals& s = p.s;
  const double span = s.i.maxCoeff() - s.i.minCoeff();
  if (!(span >
        1e-12 * std::max(s.v1.cwiseAbs().maxCoeff(), s.v2.cwiseAbs().maxCoeff()) / rec.r1_ohm))
    throw std::invalid_argument("impedance_prony: no current flows (v1 == v2): Z is undefined");
  if (automatic && p.po.noise_mixing.size() == 0 && s.size() >= 24) {
    // Noise model of the divider: independent n1, n2 on the measured channels,
    // the current's noise is (n1 − n2)/R1 (not a third independent source).
    const double s1 = estimate_noise_std(s.v1), s2 = estimate_noise_std(s.v2);
    p.po.noise_mixing.resize(3, 2);
    p.po.noise_mixing << s1, 0.0, 0.0, s2, s1 / rec.r1_ohm, -s2 / rec.r1_ohm;
  }
  p.y = stack(s);
  const std::size_t want = opt.direct_samples == PronyImpedanceOptions::kDirectFilterLength
                               ? 10 * decimation_factor(p.po, s.sample_rate_hz)
                               : opt.direct_samples;
  p.direct = static_cast<Eigen::Index>(std::min<std::size_t>(want, s.size() / 2));
  p.po.skip_samples = std::max<std::size_t>(p.po.skip_samples, static_cast<std::size_t>(p.direct));
  return p;
}

PronyImpedance finish(const PronyProblem& p, const DividerRecord& rec,
                      const PronyImpedanceOptions& opt, PronyFit fit) {
  PronyImpedance out;
  out.r1_ohm = rec.r1_ohm;
  out.fit = std::move(fit);
  if (opt.ramp_onset && rec.pretrigger_samples > 0) {
    out.onset_dt_s = 1.0 / p.s.sample_rate_hz;
    out.onset_v = {p.s.v1[0], p.s.v2[0], p.s.i[0]};
  }
  attach_direct_residual(out, p.y, p.direct);
  return out;
}

}  // namespace

PronyImpedance fit_prony_impedance(const DividerRecord& rec, const PronyImpedanceOptions& opt) {
  const PronyProblem p = prony_problem(rec, opt, !opt.prony.order);
  return finish(p, rec, opt, prony_ss(p.y, p.s.sample_rate_hz, p.po));
}

std::vector<std::optional<PronyImpedance>> fit_prony_impedance_orders(
    const DividerRecord& rec, const PronyImpedanceOptions& opt,
    const std::vector<std::size_t>& orders) {
  bool automatic = false;
  for (std::size_t q : orders) automatic = automatic || q == 0;
  const PronyProblem p = prony_problem(rec, opt, automatic);
  std::vector<std::optional<PronyImpedance>> out;
  for (auto& f : prony_ss_orders(p.y, p.s.sample_rate_hz, p.po, orders)) {
    if (f.fit) out.push_back(finish(p, rec, opt, std::move(*f.fit)));
    else out.emplace_back();
  }
  return out;
}

PronySummary summarize(const PronyFit& fit) {
  PronySummary p;
  p.order = fit.order;
  p.order_automatic = fit.order_automatic;
  for (Eigen::Index k = 0; k < fit.singular_values.size(); ++k)
    p.singular_values_normalized.push_back(fit.singular_values[k] / fit.singular_values[0]);
  p.poles = pole_table(fit);
  return p;
}

ImpedanceResult impedance_prony(const DividerRecord& rec, const Eigen::VectorXd& f_hz,
                                const PronyImpedanceOptions& opt) {
  if (f_hz.size() < 2) throw std::invalid_argument("impedance_prony: need at least 2 frequencies");
  const PronyImpedance model = fit_prony_impedance(rec, opt);
  ImpedanceResult r;
  r.method = "prony";
  r.samples_used = static_cast<std::size_t>(model.fit.samples);
  r.f_hz = f_hz;
  r.z_ohm.resize(f_hz.size());
  for (Eigen::Index k = 0; k < f_hz.size(); ++k) r.z_ohm[k] = model.z(f_hz[k]);
  r.prony = summarize(model.fit);

  const double fmin = std::max(f_hz.minCoeff(), opt.features.fmin_hz);
  const double fmax = std::min(f_hz.maxCoeff(), opt.features.fmax_hz);
  const double step = opt.feature_step_hz > 0
                          ? opt.feature_step_hz
                          : (f_hz.maxCoeff() - f_hz.minCoeff()) / double(f_hz.size() - 1) / 4.0;
  auto features_of = [&](const PronyImpedance& m) {
    auto f = find_features([&m](double f) { return m.z(f); }, fmin, fmax, step, opt.features);
    refine_features_to_modal(m, f);
    return f;
  };
  r.features = features_of(model);

  if (opt.bootstrap > 0) {
    // Parametric bootstrap: model + white noise of the fit's residual RMS on v1, v2.
    const DividerSignals s = prepare_divider(rec, "impedance_prony", opt.prep);
    Eigen::MatrixXd clean = reconstruct(model.fit, s.size());
    const Eigen::Index direct = model.direct_residual.rows();
    clean.topRows(direct) += model.direct_residual;  // the recorded early samples
    std::mt19937_64 rng(opt.bootstrap_seed);
    std::normal_distribution<double> nd;
    PronyImpedanceOptions o2 = opt;
    o2.prony.order = model.fit.order;
    std::vector<std::vector<double>> res(r.features.resonances.size()),
        anti(r.features.antiresonances.size()), cap(1);
    Eigen::VectorXd zvar = Eigen::VectorXd::Zero(f_hz.size());
    std::size_t good = 0;
    for (std::size_t b = 0; b < opt.bootstrap; ++b) {
      Eigen::MatrixXd y(s.size(), 3);
      for (Eigen::Index k = 0; k < s.size(); ++k) {
        y(k, 0) = clean(k, 0) + model.fit.residual_rms[0] * nd(rng);
        y(k, 1) = clean(k, 1) + model.fit.residual_rms[1] * nd(rng);
      }
      y.col(2) = (y.col(0) - y.col(1)) / rec.r1_ohm;
      PronyImpedance m2;
      m2.r1_ohm = rec.r1_ohm;
      m2.onset_dt_s = model.onset_dt_s;
      m2.onset_v = model.onset_v;
      try {
        PronyOptions p2 = o2.prony;
        p2.skip_samples = std::max<std::size_t>(p2.skip_samples, static_cast<std::size_t>(direct));
        m2.fit = prony_ss(y, s.sample_rate_hz, p2);
        attach_direct_residual(m2, y, direct);
      } catch (const std::invalid_argument&) {
        continue;  // a degenerate replicate carries no information
      }
      for (Eigen::Index k = 0; k < f_hz.size(); ++k)
        zvar[k] += std::norm(m2.z(f_hz[k]) - r.z_ohm[k]);
      ++good;
      const auto f2 = features_of(m2);
      accumulate(r.features.resonances, f2.resonances, res);
      accumulate(r.features.antiresonances, f2.antiresonances, anti);
      if (std::isfinite(f2.capacitance_f)) cap[0].push_back(f2.capacitance_f);
    }
    for (std::size_t k = 0; k < res.size(); ++k) r.features.resonances[k].sigma_hz = stddev(res[k]);
    for (std::size_t k = 0; k < anti.size(); ++k)
      r.features.antiresonances[k].sigma_hz = stddev(anti[k]);
    r.features.capacitance_sigma_f = stddev(cap[0]);
    if (good >= 2) r.z_sigma_ohm = (zvar / double(good)).cwiseSqrt();
  }
  return r;
}

}  // namespace piezo::dsp
