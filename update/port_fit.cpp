#include "update/port_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <optional>
#include <stdexcept>

#include "numerics/levenberg_marquardt.hpp"
#include "dsp/windows.hpp"
#include "model/transient.hpp"

namespace piezo::update {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;

// θ = [ln C_e, ln ω_k (K), ln q_k (K), ln c_k (K), (ln q_h, x_h)]; the
// pseudo-mode's frequency ω_h is held (in band its static part is degenerate
// with C_e, so a free ω_h leaves a flat valley the fit crawls along), and its
// damping ratio ζ_h = 2/(1 + e^−x_h) is bounded: unbounded, the fit can damp
// it out of existence (ζ_h ≈ 500) and settle in a side minimum with the third
// resonance 0.2 % high and 3× the noise in the output error.
double zeta_high(double x) { return 2.0 / (1.0 + std::exp(-x)); }
double zeta_high_inverse(double zeta) { return -std::log(2.0 / zeta - 1.0); }

struct Layout {
  int k = 0;
  std::vector<double> w_high;
  int size() const { return 1 + 3 * k + 2 * static_cast<int>(w_high.size()); }
  model::ModalPortModel port(const Eigen::VectorXd& th) const {
    model::ModalPortModel p;
    p.c_clamped = std::exp(th[0]);
    auto add = [&](double w, double q, double c) {
      model::PortMode m;
      m.omega = w;
      m.participation = std::sqrt(q);
      m.kappa = c;  // c_k through RayleighDamping{0, 1}
      m.symmetric = true;
      p.modes.push_back(m);
    };
    for (int i = 0; i < k; ++i)
      add(std::exp(th[1 + i]), std::exp(th[1 + k + i]), std::exp(th[1 + 2 * k + i]));
    for (std::size_t h = 0; h < w_high.size(); ++h)
      add(w_high[h], std::exp(th[1 + 3 * k + 2 * h]),
          2.0 * w_high[h] * zeta_high(th[2 + 3 * k + 2 * h]));
    return p;
  }
};

// x = q/C_e of the K modes from the anti-resonances: 1 + Σ_k x_k/(ω_k² − ω_aj²) + b_j = 0.
std::optional<Eigen::VectorXd> ratios_from_antiresonances(const std::vector<double>& wr,
                                                          const std::vector<double>& wa,
                                                          const Eigen::VectorXd& extra) {
  const int k = static_cast<int>(wr.size());
  Eigen::MatrixXd a(k, k);
  Eigen::VectorXd b(k);
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i) a(j, i) = 1.0 / (wr[i] * wr[i] - wa[j] * wa[j]);
    b[j] = -1.0 - extra[j];
  }
  Eigen::VectorXd x = a.colPivHouseholderQr().solve(b);
  if (!x.allFinite()) return std::nullopt;
  return x;
}

// Causal low-pass FIR (Blackman-windowed sinc, cutoff fc, unit DC gain),
// evaluated at every d-th sample of x (x = 0 before its first sample).
class LowpassDecimator {
 public:
  LowpassDecimator(double fs, double fc) : h_(dsp::blackman_lowpass(fs, fc)) {
    // Output every d-th sample, d = fs/(2 fc): the filtered error is then
    // sampled at about its own bandwidth, nearly white (for the covariance).
    d_ = std::max<Eigen::Index>(1, static_cast<Eigen::Index>(fs / (2.0 * fc)));
  }
  Eigen::VectorXd operator()(const Eigen::VectorXd& x) const {
    const Eigen::Index m = (x.size() + d_ - 1) / d_;
    Eigen::VectorXd y(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      const Eigen::Index n = i * d_;
      const Eigen::Index l_max = std::min<Eigen::Index>(h_.size() - 1, n);
      double acc = 0;
      for (Eigen::Index l = 0; l <= l_max; ++l) acc += h_[l] * x[n - l];
      y[i] = acc;
    }
    return y;
  }

 private:
  Eigen::VectorXd h_;
  Eigen::Index d_ = 1;
};

}  // namespace

double port_capacitance(const model::ModalPortModel& port, double f_hz) {
  const double w2 = std::pow(kTwoPi * f_hz, 2);
  double c = port.c_clamped + port.c_residual;
  for (const auto& m : port.modes)
    c += m.participation * m.participation / (m.omega * m.omega - w2);
  return c;
}

std::vector<double> port_antiresonances_hz(const model::ModalPortModel& port, bool damped) {
  // f(λ) = C_e + Σ q_k/(ω_k² − λ) rises monotonically from −∞ to +∞ between
  // consecutive ω_k² (and from −∞ to C_e > 0 above the last): one root each.
  std::vector<double> w2;
  for (const auto& m : port.modes) w2.push_back(m.omega * m.omega);
  std::sort(w2.begin(), w2.end());
  auto f = [&](double lam) {
    double s = port.c_clamped + port.c_residual;
    for (const auto& m : port.modes)
      s += m.participation * m.participation / (m.omega * m.omega - lam);
    return s;
  };
  // Q/V(s) with the modal damping c_k = kappa_k (RayleighDamping{0, 1}).
  using cd = std::complex<double>;
  auto g = [&](cd s) {
    cd v = port.c_clamped + port.c_residual;
    for (const auto& m : port.modes)
      v += m.participation * m.participation / (m.omega * m.omega + s * s + m.kappa * s);
    return v;
  };
  std::vector<double> out;
  for (std::size_t i = 0; i < w2.size(); ++i) {
    double lo = w2[i] * (1 + 1e-14), hi = i + 1 < w2.size() ? w2[i + 1] * (1 - 1e-14) : 4.0 * w2[i];
    if (i + 1 == w2.size())
      while (f(hi) < 0 && hi < 1e6 * w2[i]) hi *= 2;
    if (!(f(lo) < 0 && f(hi) > 0)) continue;
    for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
      const double mid = 0.5 * (lo + hi);
      (f(mid) < 0 ? lo : hi) = mid;
    }
    const double w = std::sqrt(0.5 * (lo + hi));
    double result = w;
    if (damped) {
      // Newton on the complex zero of Q/V next to the undamped root; its natural
      // frequency |s*| is what the short-/open-circuit modal frequency is for
      // (stiffness-)proportional damping, and what the data determine.
      cd s(0.0, w);
      bool ok = false;
      for (int it = 0; it < 60; ++it) {
        const cd h(1e-7 * w, 0.0);
        const cd d = (g(s + h) - g(s - h)) / (2.0 * h);
        if (std::abs(d) == 0.0) break;
        const cd step = g(s) / d;
        s -= step;
        if (std::abs(step) < 1e-13 * w) {
          ok = true;
          break;
        }
      }
      // Damping moves |s*| by O(ζ²) only; anything further is another zero.
      if (ok && s.real() < 0 && std::abs(std::abs(s) / w - 1) < 0.01) result = std::abs(s);
    }
    out.push_back(result / kTwoPi);
  }
  return out;
}

PortFitResult fit_port_model(std::span<const double> v1, std::span<const double> v2, double fs,
                             double r1_ohm, const PortFitStart& start, const PortFitOptions& opt) {
  const char* fn = "fit_port_model";
  const int k = static_cast<int>(start.resonances_hz.size());
  if (k < 1) throw std::invalid_argument(std::string(fn) + ": needs at least one resonance");
  if (start.antiresonances_hz.size() < start.resonances_hz.size())
    throw std::invalid_argument(std::string(fn) + ": needs one anti-resonance per resonance");
  if (v1.size() != v2.size() || v1.size() < static_cast<std::size_t>(8 * k + 16))
    throw std::invalid_argument(std::string(fn) +
                                ": v1 and v2 must have the same, sufficient length");
  if (!(fs > 0) || !(r1_ohm > 0) || !(start.capacitance_f > 0))
    throw std::invalid_argument(std::string(fn) + ": rate, R1 and capacitance must be > 0");
  for (std::size_t i = 0; i < v1.size(); ++i)
    if (!std::isfinite(v1[i]) || !std::isfinite(v2[i]))
      throw std::invalid_argument(std::string(fn) + ": signals contain NaN or Inf");
  std::vector<double> wr, wa;
  for (int i = 0; i < k; ++i) {
    wr.push_back(kTwoPi * start.resonances_hz[i]);
    wa.push_back(kTwoPi * start.antiresonances_hz[i]);
    if (!(wr[i] > 0) || !(wa[i] > wr[i]) || (i > 0 && !(wr[i] > wa[i - 1])))
      throw std::invalid_argument(
          std::string(fn) +
          ": resonances and anti-resonances must interlace (f_r1 < f_a1 < f_r2 …)");
  }

  // Start: anti-resonances → q_k/C_e, low-frequency capacitance → C_e (eqs of port_model.hpp).
  Layout lay{k, {}};
  if (opt.high_mode)
    for (double fct : opt.high_mode_factors) lay.w_high.push_back(fct * wa.back());
  // Start: each pseudo-mode with a static share of 5 % of C_e and ζ = 5 %.
  std::vector<double> x_high;
  for (double w : lay.w_high) x_high.push_back(0.05 * w * w);
  Eigen::VectorXd extra = Eigen::VectorXd::Zero(k);
  for (std::size_t h = 0; h < lay.w_high.size(); ++h)
    for (int j = 0; j < k; ++j)
      extra[j] += x_high[h] / (lay.w_high[h] * lay.w_high[h] - wa[j] * wa[j]);
  const auto x = ratios_from_antiresonances(wr, wa, extra);
  if (!x) throw std::invalid_argument(std::string(fn) + ": cannot start from these features");
  double s0 = 1.0 + 0.05 * static_cast<double>(lay.w_high.size());
  for (int i = 0; i < k; ++i) s0 += std::max((*x)[i], 1e-6 * wr[i] * wr[i]) / (wr[i] * wr[i]);
  const double ce = start.capacitance_f / s0;
  Eigen::VectorXd th(lay.size());
  th[0] = std::log(ce);
  for (int i = 0; i < k; ++i) {
    const double zeta = i < static_cast<int>(start.damping_ratios.size()) &&
                                std::isfinite(start.damping_ratios[i]) &&
                                start.damping_ratios[i] > 0
                            ? start.damping_ratios[i]
                            : 0.01;
    th[1 + i] = std::log(wr[i]);
    th[1 + k + i] = std::log(ce * std::max((*x)[i], 1e-6 * wr[i] * wr[i]));
    th[1 + 2 * k + i] = std::log(2.0 * zeta * wr[i]);
  }
  for (std::size_t h = 0; h < lay.w_high.size(); ++h) {
    th[1 + 3 * k + 2 * h] = std::log(ce * x_high[h]);
    th[2 + 3 * k + 2 * h] = zeta_high_inverse(0.25);
  }

  const auto n = static_cast<Eigen::Index>(v2.size());
  const Eigen::Map<const Eigen::VectorXd> y(v2.data(), n);
  model::DividerCircuit circuit;
  circuit.r1_ohm = r1_ohm;
  circuit.c_parallel_f = opt.fixture_capacitance_f;
  circuit.r_lead_ohm = opt.lead_resistance_ohm;
  circuit.validate();
  const double band = opt.band_hz > 0 ? opt.band_hz : 1.5 * start.antiresonances_hz[k - 1];
  if (!(band < 0.5 * fs)) throw std::invalid_argument(std::string(fn) + ": band above Nyquist");
  const LowpassDecimator lowpass(fs, band);
  auto residual = [&](const Eigen::VectorXd& t) -> std::optional<Eigen::VectorXd> {
    try {
      const auto sim = model::simulate_divider(lay.port(t), {0.0, 1.0}, circuit, v1, fs);
      Eigen::VectorXd r = lowpass(Eigen::Map<const Eigen::VectorXd>(sim.data(), n) - y);
      if (!r.allFinite()) return std::nullopt;
      return r;
    } catch (const std::invalid_argument&) {
      return std::nullopt;
    }
  };
  // Jacobian of the filtered output error with respect to the parameters in `free`.
  auto jacobian = [&](const Eigen::VectorXd& t, const std::vector<int>& free,
                      Eigen::MatrixXd& j) -> bool {
    j.resize(0, static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < free.size(); ++c) {
      const int p = free[c];
      // ω enters through phases ωt of hundreds of radians: a smaller step.
      const double h = p >= 1 && p <= k ? 1e-7 : 1e-5;
      Eigen::VectorXd tp = t, tm = t;
      tp[p] += h;
      tm[p] -= h;
      const auto rp = residual(tp), rm = residual(tm);
      if (!rp || !rm) return false;
      if (j.rows() != rp->size()) j.resize(rp->size(), static_cast<Eigen::Index>(free.size()));
      j.col(static_cast<Eigen::Index>(c)) = (*rp - *rm) / (2.0 * h);
    }
    return true;
  };

  // Resonances, anti-resonances and C(f_L) of a parameter vector.
  auto features_of = [&](const Eigen::VectorXd& t) {
    const auto p = lay.port(t);
    Eigen::VectorXd f(2 * k + 1);
    const auto anti = port_antiresonances_hz(p, true);
    for (int i = 0; i < k; ++i) {
      f[i] = std::exp(t[1 + i]) / kTwoPi;
      f[k + i] = i < static_cast<int>(anti.size()) ? anti[i] : NAN;
    }
    f[2 * k] = port_capacitance(p, opt.low_f_hz);
    return f;
  };
  PortFitResult res;
  auto r = residual(th);
  if (!r) throw std::invalid_argument(std::string(fn) + ": the starting model cannot be simulated");
  double cost = 0.5 * r->squaredNorm();
  Eigen::MatrixXd j;
  // Levenberg–Marquardt (numerics/levenberg_marquardt) over the parameters in
  // `free`, the others held; true when converged.
  auto levenberg_marquardt = [&](const std::vector<int>& free, int max_iterations) {
    auto full = [&](const Eigen::VectorXd& u) {
      Eigen::VectorXd t = th;
      for (std::size_t c = 0; c < free.size(); ++c) t[free[c]] = u[static_cast<Eigen::Index>(c)];
      return t;
    };
    Eigen::VectorXd u0(static_cast<Eigen::Index>(free.size()));
    for (std::size_t c = 0; c < free.size(); ++c) u0[static_cast<Eigen::Index>(c)] = th[free[c]];
    numerics::LmProblem pb;
    pb.residual = [&](const Eigen::VectorXd& u) { return residual(full(u)); };
    pb.jacobian = [&](const Eigen::VectorXd& u, const Eigen::VectorXd&, Eigen::MatrixXd& jac,
                      const numerics::LmJacobianCall&) { return jacobian(full(u), free, jac); };
    // Converged also when the features stop moving: C_e and the pseudo-mode's
    // static share trade off along a nearly flat valley that LM crawls through
    // without changing them.
    Eigen::VectorXd f_prev = features_of(th);
    pb.converged_after_step = [&](const numerics::LmState& st) {
      const Eigen::VectorXd f_now = features_of(full(st.x));
      const double moved = ((f_now - f_prev).array() / f_prev.array()).abs().maxCoeff();
      f_prev = f_now;
      return moved < opt.feature_tolerance;
    };
    numerics::LmSettings ls;  // this fit's damping before the shared engine
    ls.max_iterations = max_iterations;
    ls.max_tries = 16;
    ls.step_tolerance = opt.step_tolerance;
    ls.jacobian_at_answer = false;  // the covariance below takes its own J at the answer
    const numerics::LmRun run = numerics::levenberg_marquardt(pb, u0, ls);
    res.iterations += run.iterations;
    if (run.stop == numerics::LmRun::Stop::bad_start) {
      res.message = "the model could not be simulated at the current estimate";
      return false;
    }
    th = full(run.x);
    r = run.r;
    cost = run.cost;
    switch (run.stop) {
      case numerics::LmRun::Stop::converged:
        return true;
      case numerics::LmRun::Stop::jacobian_failed:
        res.message = "the model could not be simulated near the current estimate";
        return false;
      case numerics::LmRun::Stop::stalled:
        // No step lowers the error any more, and the residual is not orthogonal
        // to the Jacobian's columns (cosine >= 1e-4): not a minimum.
        res.message =
            "no decrease of the output error (Levenberg-Marquardt stalled, gradient cosine " +
            std::to_string(run.stall_cosine) + ")";
        return false;
      default:
        res.message = "did not converge in " + std::to_string(max_iterations) + " iterations";
        return false;
    }
  };
  // Stage 1 holds the resonances at Prony's values and fits the amplitudes,
  // dampings and capacitances (from the rough start, letting ω move at once can
  // drop the third mode into a side minimum 0.2 % off); stage 2 frees all.
  std::vector<int> all(static_cast<std::size_t>(th.size())), no_omega;
  for (int p = 0; p < th.size(); ++p) {
    all[static_cast<std::size_t>(p)] = p;
    const bool pseudo_damping = p >= 1 + 3 * k && (p - 1 - 3 * k) % 2 == 1;
    if ((p < 1 || p > k) && !pseudo_damping) no_omega.push_back(p);
  }
  levenberg_marquardt(no_omega, opt.max_iterations);
  res.message.clear();
  res.converged = levenberg_marquardt(all, opt.max_iterations);

  res.port = lay.port(th);
  const auto n_r = r->size();
  res.residual_rms_v = std::sqrt(2.0 * cost / static_cast<double>(n_r));
  const Eigen::VectorXd f0 = features_of(th);
  auto& mf = res.features;
  for (int i = 0; i < k; ++i) {
    mf.resonances_hz.push_back(f0[i]);
    mf.antiresonances_hz.push_back(f0[k + i]);
  }
  mf.low_z_hz = opt.low_f_hz;
  mf.low_z_ohm = 1.0 / (kTwoPi * opt.low_f_hz * f0[2 * k]);
  bool interlaced = f0.allFinite() && f0[2 * k] > 0;
  for (int i = 0; i < k && interlaced; ++i)
    interlaced = f0[k + i] > f0[i] && (i + 1 == k || f0[i + 1] > f0[k + i]);
  if (!interlaced) {
    res.converged = false;
    res.message = "the fitted model's resonances and anti-resonances do not interlace";
    return res;
  }
  if (jacobian(th, all, j)) {
    const double s2 = 2.0 * cost / static_cast<double>(std::max<Eigen::Index>(1, n_r - th.size()));
    const Eigen::MatrixXd cov =
        s2 * (j.transpose() * j).ldlt().solve(Eigen::MatrixXd::Identity(th.size(), th.size()));
    Eigen::MatrixXd df(f0.size(), th.size());
    for (Eigen::Index p = 0; p < th.size(); ++p) {
      Eigen::VectorXd tp = th, tm = th;
      tp[p] += 1e-7;
      tm[p] -= 1e-7;
      df.col(p) = (features_of(tp) - features_of(tm)) / 2e-7;
    }
    const Eigen::VectorXd var = (df * cov * df.transpose()).diagonal();
    if (var.allFinite() && (var.array() > 0).all()) {
      for (int i = 0; i < k; ++i) {
        mf.resonance_sigma_hz.push_back(std::sqrt(var[i]));
        mf.antiresonance_sigma_hz.push_back(std::sqrt(var[k + i]));
      }
      mf.low_z_sigma_ohm = mf.low_z_ohm * std::sqrt(var[2 * k]) / f0[2 * k];
    }
  }
  return res;
}

}  // namespace piezo::update
