#include "update/output_error.hpp"

#include <Eigen/Eigenvalues>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <memory>
#include <thread>
#include <atomic>
#include <exception>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "dsp/fft.hpp"
#include "dsp/prony_ss.hpp"
#include "dsp/windows.hpp"
#include "model/bench_response.hpp"
#include "model/effects.hpp"

namespace piezo::update {

namespace {

constexpr double kTwoPi = 2.0 * M_PI;
using cd = std::complex<double>;
constexpr int kParams = 5;  // ln YE11, nu12 (relative), ln d31, ln εT33, ln β (or ln η, η = 1/Qm)

[[noreturn]] void fail(const std::string& msg) {
  throw std::invalid_argument("fit_output_error: " + msg);
}

// The parameter vector θ relative to the nominal constants.
struct Coordinates5 {
  TubeParams p0;
  double beta0 = 1e-7;  // the loss at x[4] = 0: β (rayleigh) or η = 1/Qm (complex constants)
  OeDamping damping = OeDamping::rayleigh;
  TubeParams params(const Eigen::VectorXd& x) const {
    TubeParams p = p0;
    p.y_e11 = p0.y_e11 * std::exp(x[0]);
    p.nu12 = p0.nu12 * (1.0 + x[1]);
    p.d31 = p0.d31 * std::exp(x[2]);
    p.eps_t33 = p0.eps_t33 * std::exp(x[3]);
    return p;
  }
  double loss(const Eigen::VectorXd& x) const { return beta0 * std::exp(x[4]); }
  double beta(const Eigen::VectorXd& x) const {
    return damping == OeDamping::rayleigh ? loss(x) : 0.0;
  }
  double eta(const Eigen::VectorXd& x) const {
    return damping == OeDamping::complex_constants ? loss(x) : 0.0;
  }
};

// Shots averaged per (length, pretrigger) group; the largest group is used.
struct Averaged {
  std::vector<double> v1, v2;
  std::size_t pretrigger = 0;
  std::vector<std::vector<double>> dev1, dev2;  // each shot minus the average (K ≥ 2)
  int shots = 0;
};

Averaged average(const OeData& d) {
  if (d.shots.empty()) fail("no shots");
  // Group by (length, pretrigger): the largest group.
  std::size_t best = 0, best_count = 0;
  for (std::size_t i = 0; i < d.shots.size(); ++i) {
    std::size_t c = 0;
    for (const auto& s : d.shots)
      c += s.v1.size() == d.shots[i].v1.size() && s.pretrigger == d.shots[i].pretrigger;
    if (c > best_count) best = i, best_count = c;
  }
  const OeShot& ref = d.shots[best];
  const std::size_t n = ref.v1.size();
  Averaged a;
  a.v1.assign(n, 0.0);
  a.v2.assign(n, 0.0);
  a.pretrigger = ref.pretrigger;
  std::vector<const OeShot*> used;
  for (const auto& s : d.shots) {
    if (s.v1.size() != n || s.pretrigger != ref.pretrigger) continue;
    if (s.v2.size() != n) fail("a shot's v1 and v2 differ in length");
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(s.v1[i]) || !std::isfinite(s.v2[i])) fail("a shot holds NaN or Inf samples");
      a.v1[i] += s.v1[i];
      a.v2[i] += s.v2[i];
    }
    used.push_back(&s);
  }
  a.shots = static_cast<int>(used.size());
  for (auto& v : a.v1) v /= a.shots;
  for (auto& v : a.v2) v /= a.shots;
  if (a.shots >= 2)
    for (const OeShot* s : used) {
      std::vector<double> d1(n), d2(n);
      for (std::size_t i = 0; i < n; ++i) {
        d1[i] = s->v1[i] - a.v1[i];
        d2[i] = s->v2[i] - a.v2[i];
      }
      a.dev1.push_back(std::move(d1));
      a.dev2.push_back(std::move(d2));
    }
  // DAQ offsets: the idle level before the drive (with a pretrigger of its own).
  if (a.pretrigger >= 16 && a.pretrigger < n) {
    double m1 = 0, m2 = 0;
    for (std::size_t i = 0; i < a.pretrigger; ++i) {
      m1 += a.v1[i];
      m2 += a.v2[i];
    }
    m1 /= double(a.pretrigger);
    m2 /= double(a.pretrigger);
    for (std::size_t i = 0; i < n; ++i) {
      a.v1[i] -= m1;
      a.v2[i] -= m2;
    }
  }
  return a;
}

// The filtered, decimated output error of one parameter vector.
class Problem {
 public:
  Problem(model::ModalSolver& solver, const MaterialClass& cls, const Coordinates5& co,
          const Averaged& rec, const OeData& data, double band_hz, const model::ModalOptions& modal)
      : solver_(solver), cls_(cls), co_(co), modal_(modal), r1_(data.circuit.r1_ohm),
        fs_(data.sample_rate_hz), n_(rec.v1.size()),
        nfft_(dsp::good_fft_size(std::max<std::size_t>(4 * n_, 1u << 14))), fft_(nfft_) {
    fx_.series_resistance_ohm = data.circuit.r_lead_ohm;
    fx_.parallel_capacitance_f = data.circuit.c_parallel_f;
    fx_.daq_input_resistance_ohm = data.circuit.r_daq_ohm;
    fx_.channel_skew_s = data.v2_delay_s;
    fx_.mass_loading = modal_.end_mass_fraction;
    const Eigen::VectorXd h = dsp::blackman_lowpass(fs_, band_hz);
    if (static_cast<std::size_t>(h.size()) > nfft_ - n_) fail("record too short for the band");
    kmax_ = std::min<std::size_t>(fft_.bins() - 1,
                                  static_cast<std::size_t>(std::ceil(2.5 * band_hz * double(nfft_) / fs_)));
    std::vector<cd> hl(fft_.bins()), v1(fft_.bins()), v2(fft_.bins());
    fft_.forward(h.data(), static_cast<std::size_t>(h.size()), hl.data());
    fft_.forward(rec.v1.data(), n_, v1.data());
    fft_.forward(rec.v2.data(), n_, v2.data());
    lv1_.resize(kmax_ + 1);
    ly_.resize(kmax_ + 1);
    l_.resize(kmax_ + 1);
    for (std::size_t k = 0; k <= kmax_; ++k) {
      l_[k] = hl[k];
      lv1_[k] = hl[k] * v1[k];
      ly_[k] = hl[k] * v2[k];
    }
    decim_ = std::max<std::size_t>(1, static_cast<std::size_t>(fs_ / (2.0 * band_hz)));
    for (std::size_t i = 0; i < n_; i += decim_) idx_.push_back(i);
    spec_.assign(fft_.bins(), cd(0.0, 0.0));
    buf_.resize(n_);
    cache_.reserve(kCache);
  }

  std::size_t samples() const { return idx_.size(); }
  int evaluations() const { return evaluations_; }  // FE port models built

  // The FE port model of the material part of x (θ without β) with an end
  // mass, from a small cache: the Jacobian's β and effect columns, the
  // type-B perturbations of the chain and the re-evaluations at an answer
  // need no new modal solve. nullptr when the model cannot be built.
  const model::ModalPortModel* port_of(const Eigen::VectorXd& x, double end_mass) {
    const Key key = key_of(x, end_mass);
    if (Cached* c = cached(key)) return c->port ? &*c->port : nullptr;
    return insert(key, build(solver_, key));
  }

  // The port models of several points at once (an exact Jacobian's columns,
  // a grid of starts), those not cached built on `threads` threads: this
  // solver and a second one on the same tube. A port model is a function of
  // its key alone (each solve starts from Spectra's fixed initial vector), so
  // the answers do not depend on the thread count.
  void prefetch(const std::vector<std::pair<Eigen::VectorXd, double>>& points) {
    std::vector<Key> todo;
    for (const auto& [x, mass] : points) {
      const Key key = key_of(x, mass);
      if (!cached(key) && std::find(todo.begin(), todo.end(), key) == todo.end()) todo.push_back(key);
    }
    if (todo.empty()) return;
    std::vector<std::optional<model::ModalPortModel>> built(todo.size());
    if (threads_ > 1 && todo.size() > 1) {
      model::ModalSolver& second = second_solver();
      // The second thread takes the odd points (one FE model each, equal work).
      std::thread other([&] {
        for (std::size_t i = 1; i < todo.size(); i += 2) built[i] = build(second, todo[i]);
      });
      for (std::size_t i = 0; i < todo.size(); i += 2) built[i] = build(solver_, todo[i]);
      other.join();
    } else {
      for (std::size_t i = 0; i < todo.size(); ++i) built[i] = build(solver_, todo[i]);
    }
    for (std::size_t i = 0; i < todo.size(); ++i) insert(todo[i], std::move(built[i]));
  }
  void set_threads(int n) { threads_ = std::max(1, n); }
  int threads() const { return threads_; }

  // The same problem for another thread (the effect scan): its own FFT plan
  // and buffers, `solver` for its FE models, this one's cache and tangent.
  // Construct and destroy it on the thread that owns this one (FFTW's planner
  // is not thread-safe; executing distinct plans is).
  Problem(const Problem& o, model::ModalSolver& solver)
      : solver_(solver), cls_(o.cls_), co_(o.co_), modal_(o.modal_), r1_(o.r1_), fx_(o.fx_), free_(o.free_),
        fs_(o.fs_), n_(o.n_), nfft_(o.nfft_), fft_(o.nfft_), kmax_(o.kmax_), decim_(o.decim_), l_(o.l_),
        lv1_(o.lv1_), ly_(o.ly_), spec_(o.spec_), buf_(o.buf_), idx_(o.idx_), tangent_(o.tangent_),
        cache_(o.cache_), clock_(o.clock_) {}
  Problem(const Problem&) = delete;
  Problem& operator=(const Problem&) = delete;
  // A second solver on the same tube (built on first use): prefetch's second
  // thread, or a forked Problem's.
  model::ModalSolver& second_solver() {
    if (!solver2_) solver2_ = std::make_unique<model::ModalSolver>(solver_.model());
    return *solver2_;
  }

  // The bench's known effects (OeData: a measured fixture's lead R, Cp, DAQ
  // input R and skew), as the catalogue's EffectSet (model/effects.hpp).
  const model::EffectSet& effects() const { return fx_; }
  // … with the free effect (scan_effects) at x's sixth coordinate.
  model::EffectSet effects_at(const Eigen::VectorXd& x) const {
    model::EffectSet fx = fx_;
    if (x.size() > kParams && free_) free_(fx, x[kParams]);
    return fx;
  }

  // T(f_k) = v2/v1 as recorded, for parameters x, with the bench's effects
  // (model/bench_response.hpp: the same forward model as the gap diagnosis
  // and the simulated bench's frequency-domain twin); empty when the model
  // cannot be built.
  std::optional<std::vector<cd>> transfer(const Eigen::VectorXd& x) { return transfer(x, effects_at(x)); }
  // A catalogue effect as a sixth coordinate of x (scan_effects below).
  void free_effect(std::function<void(model::EffectSet&, double)> apply) { free_ = std::move(apply); }
  std::optional<std::vector<cd>> transfer(const Eigen::VectorXd& x, const model::EffectSet& fx) {
    const model::ModalPortModel* pp = port_of(x, fx.mass_loading);
    if (!pp) return std::nullopt;
    return transfer_of(*pp, co_.beta(x), co_.eta(x), fx);
  }

  // The port models' tangent ∂port/∂x_c (c < 4: the constants) by forward
  // differences at x_ref, from the models an exact Jacobian built there. Near
  // x_ref (|Δx| ≤ kTangentReach in every constant's coordinate, the same end
  // mass) a material column of the Jacobian is then the residual at x with
  // the port model port(x) + h·∂port/∂x_c — the frequency response still
  // computed exactly at x, only the modal quantities' slopes taken from
  // x_ref, a few per mille off: no FE model per column. The residuals, the
  // costs and the answers stay exact; an optimiser's fixed point moves by that
  // error times the residual's projection, a tiny fraction of a sigma.
  void set_tangent(const Eigen::VectorXd& x, double h) { set_tangent(x, h, effects_at(x).mass_loading); }
  void set_tangent(const Eigen::VectorXd& x, double h, double mass) {
    tangent_.valid = false;
    const model::ModalPortModel* base = port_of(x, mass);
    if (!base) return;
    const model::ModalPortModel b = *base;
    for (int c = 0; c < 4; ++c) {
      Eigen::VectorXd xp = x;
      xp[c] += h;
      const model::ModalPortModel* p = port_of(xp, mass);
      if (!p || !same_structure(*p, b)) return;
      // The largest relative slope of an active mode's ω or |p| in this constant.
      double slope = 0;
      for (std::size_t i = 0; i < b.modes.size(); ++i) {
        const auto &mb = b.modes[i], &mp = p->modes[i];
        const double pa = std::abs(mb.participation);
        if (!(mb.omega > 0) || pa * pa < kActiveCoupling * mb.omega * mb.omega * b.c_clamped) continue;
        slope = std::max({slope, std::abs(std::abs(mp.participation) - pa) / (pa * h),
                          std::abs(mp.omega - mb.omega) / (mb.omega * h)});
      }
      tangent_.slope[static_cast<std::size_t>(c)] = slope;
      tangent_.plus[static_cast<std::size_t>(c)] = *p;
    }
    tangent_.base = b;
    tangent_.x_ref = x.head<4>();
    tangent_.mass = mass;
    tangent_.h = h;
    tangent_.valid = true;
  }
  bool tangent_near(const Eigen::VectorXd& x) { return tangent_near(x, effects_at(x).mass_loading); }
  // … and it still holds there: x's own port model is its linear prediction
  // from x_ref to within kTangentTolerance in every electrically active mode's
  // frequency and participation. Two modes near a veering (an avoided
  // crossing, where a few per mille of a constant swaps their shapes and
  // participations) fail it: their columns are computed exactly.
  bool tangent_near(const Eigen::VectorXd& x, double mass) {
    if (!tangent_.valid || mass != tangent_.mass ||
        (x.head<4>() - tangent_.x_ref).cwiseAbs().maxCoeff() > kTangentReach)
      return false;
    const model::ModalPortModel* at = port_of(x, mass);
    if (!at || !same_structure(*at, tangent_.base)) return false;
    model::ModalPortModel q = tangent_.base;
    for (int c = 0; c < 4; ++c) shift(q, tangent_.plus[static_cast<std::size_t>(c)], (x[c] - tangent_.x_ref[c]) / tangent_.h);
    for (std::size_t i = 0; i < q.modes.size(); ++i) {
      const auto &a = at->modes[i], &b = q.modes[i];
      const double pa = std::abs(a.participation);
      if (!(a.omega > 0) || pa * pa < kActiveCoupling * a.omega * a.omega * at->c_clamped) continue;
      if (std::abs(b.omega - a.omega) > kTangentOmegaTolerance * a.omega ||
          std::abs(b.participation - pa) > kTangentTolerance * pa)
        return false;
    }
    return true;
  }
  // T at x on the tangent anchored at a point whose model is cached:
  // port(anchor) + Σ_c (x_c − anchor_c)·∂port/∂x_c — no FE model; exact at
  // the anchor, its slopes x_ref's (a trial step's screening). Empty when
  // the anchor is not near x_ref or x not near the anchor.
  std::optional<std::vector<cd>> tangent_model(const Eigen::VectorXd& anchor, const Eigen::VectorXd& x) {
    const model::EffectSet fx = effects_at(x);
    if (!tangent_near(anchor, fx.mass_loading) || effects_at(anchor).mass_loading != fx.mass_loading ||
        (x.head<4>() - anchor.head<4>()).cwiseAbs().maxCoeff() > kTangentReach)
      return std::nullopt;
    // … and only as far as its slopes say the modes move by a few percent:
    // near a veering a participation changes by 6 % per 1e-4 of a constant
    // (refsim-like tube, dielectric loss 0.03), and a screen extrapolated to a
    // 1 % step refused every good step of the loss's run.
    double change = 0;
    for (int c = 0; c < 4; ++c) change += std::abs(x[c] - anchor[c]) * tangent_.slope[static_cast<std::size_t>(c)];
    if (!(change <= kScreenChange)) return std::nullopt;
    const model::ModalPortModel* at = port_of(anchor, fx.mass_loading);
    if (!at || !same_structure(*at, tangent_.base)) return std::nullopt;
    model::ModalPortModel p = *at;
    for (int c = 0; c < 4; ++c) shift(p, tangent_.plus[static_cast<std::size_t>(c)], (x[c] - anchor[c]) / tangent_.h);
    return transfer_of(p, co_.beta(x), co_.eta(x), fx);
  }
  // T at x with the constant c moved by h, through the tangent (tangent_near).
  std::optional<std::vector<cd>> tangent_transfer(const Eigen::VectorXd& x, int c, double h) {
    return tangent_transfer(x, c, h, effects_at(x));
  }
  std::optional<std::vector<cd>> tangent_transfer(const Eigen::VectorXd& x, int c, double h,
                                                  const model::EffectSet& fx) {
    const model::ModalPortModel* at = port_of(x, fx.mass_loading);
    if (!at || !same_structure(*at, tangent_.base)) return std::nullopt;
    model::ModalPortModel p = *at;
    shift(p, tangent_.plus[static_cast<std::size_t>(c)], h / tangent_.h);
    return transfer_of(p, co_.beta(x), co_.eta(x), fx);
  }

  // Filtered output error for a given transfer.
  Eigen::VectorXd residual_of(const std::vector<cd>& t) {
    for (std::size_t k = 0; k <= kmax_; ++k) spec_[k] = t[k] * lv1_[k] - ly_[k];
    return invert();
  }

  // Filtered output error (volts) at the decimated samples.
  std::optional<Eigen::VectorXd> residual(const Eigen::VectorXd& x) {
    const auto t = transfer(x);
    if (!t) return std::nullopt;
    return residual_of(*t);
  }

  // L ∗ (T ∗ d1 − d2) at the decimated samples (a shot's deviation from the mean).
  Eigen::VectorXd deviation(const std::vector<cd>& t, const std::vector<double>& d1,
                            const std::vector<double>& d2) {
    std::vector<cd> a(fft_.bins()), b(fft_.bins());
    fft_.forward(d1.data(), n_, a.data());
    fft_.forward(d2.data(), n_, b.data());
    for (std::size_t k = 0; k <= kmax_; ++k) spec_[k] = l_[k] * (t[k] * a[k] - b[k]);
    return invert();
  }

  // Expected |DFT|² shape of the decimated residual (bins j = 0..M/2 of its
  // M-point DFT) for white noise σ1 on v1 and σ2 on v2: |L|²(σ1²|T|² + σ2²),
  // folded over the aliases of the decimation.
  Eigen::VectorXd residual_psd(const std::vector<cd>& t, double s1, double s2) const {
    const std::size_t m = idx_.size();
    const double fs_dec = fs_ / double(decim_);
    Eigen::VectorXd p = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m / 2 + 1));
    auto at = [&](double f) {
      const auto k = static_cast<std::size_t>(std::lround(f * double(nfft_) / fs_));
      return k <= kmax_ ? std::norm(l_[k]) * (s1 * s1 * std::norm(t[k]) + s2 * s2) : 0.0;
    };
    for (std::size_t j = 0; j <= m / 2; ++j) {
      const double f = double(j) * fs_dec / double(m);
      double v = 0;
      for (int a = 0; a < 8; ++a) {
        v += at(f + a * fs_dec);
        if (a > 0) v += at(a * fs_dec - f);
      }
      p[static_cast<Eigen::Index>(j)] = v;
    }
    return p;
  }
  double residual_bin_hz() const { return fs_ / double(decim_) / double(idx_.size()); }

  // The residual in frequency at x (update/residual_regions.hpp): every r-th
  // bin of the padded transform (r = nfft/n: bins about 1/T_record apart,
  // nearly independent) in the low-pass's passband, above the lowest two
  // (the offsets), with its variance n·|L|²(σ1²|T|² + σ2²) under white noise
  // σ1 on v1 and σ2 on v2, the model's admittance and ∂T/∂Y.
  std::optional<ResidualSpectrum> residual_spectrum(const Eigen::VectorXd& x, double s1, double s2) {
    return residual_spectrum(x, effects_at(x), s1, s2);
  }
  std::optional<ResidualSpectrum> residual_spectrum(const Eigen::VectorXd& x, const model::EffectSet& fx, double s1,
                                                    double s2) {
    const model::ModalPortModel* pp = port_of(x, fx.mass_loading);
    if (!pp) return std::nullopt;
    const model::RayleighDamping damp{0.0, co_.beta(x)};
    const std::size_t r = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(double(nfft_) / double(n_))));
    double lmax = 0;
    for (std::size_t k = 0; k <= kmax_; ++k) lmax = std::max(lmax, std::abs(l_[k]));
    ResidualSpectrum s;
    for (std::size_t k = 2 * r; k <= kmax_; k += r) {
      if (std::abs(l_[k]) < 0.5 * lmax) continue;
      const double w = kTwoPi * fs_ * double(k) / double(nfft_);
      const cd y = model::tube_admittance(*pp, damp, fx, w, co_.eta(x));
      const cd t = model::recorded_transfer(y, fx, r1_, w);
      const cd dy = 1e-6 * std::abs(y);
      const cd dt = (model::recorded_transfer(y + dy, fx, r1_, w) - t) / dy;
      const double var = double(n_) * std::norm(l_[k]) * (s1 * s1 * std::norm(t) + s2 * s2);
      if (!(var > 0) || !std::isfinite(var)) continue;
      s.f_hz.push_back(w / kTwoPi);
      s.e.push_back(t * lv1_[k] - ly_[k]);
      s.lv1.push_back(lv1_[k]);
      s.t.push_back(t);
      s.dt_dy.push_back(dt);
      s.y_tube.push_back(y);
      s.var.push_back(var);
    }
    return s;
  }

  // σ of the filtered error for white noise σ1 on v1 and σ2 on v2 (Parseval).
  double propagated_sigma(const std::vector<cd>& t, double s1, double s2) const {
    double a1 = 0, a2 = 0;
    for (std::size_t k = 0; k <= kmax_; ++k) {
      const double w = (k == 0 || 2 * k == nfft_) ? 1.0 : 2.0;
      a1 += w * std::norm(l_[k] * t[k]);
      a2 += w * std::norm(l_[k]);
    }
    return std::sqrt((s1 * s1 * a1 + s2 * s2 * a2) / double(nfft_));
  }

 private:
  // The same modes in the same order (a mode crossing the truncation or the
  // residual pseudo-mode appearing changes the list: no tangent across it).
  static bool same_structure(const model::ModalPortModel& a, const model::ModalPortModel& b) {
    if (a.modes.size() != b.modes.size()) return false;
    for (std::size_t i = 0; i < a.modes.size(); ++i)
      if (a.modes[i].symmetric != b.modes[i].symmetric || a.modes[i].residual != b.modes[i].residual) return false;
    return true;
  }
  // p += k·(plus − base), the tangent's difference (same_structure).
  void shift(model::ModalPortModel& p, const model::ModalPortModel& plus, double k) const {
    const model::ModalPortModel& base = tangent_.base;
    p.c_clamped += k * (plus.c_clamped - base.c_clamped);
    p.c_static += k * (plus.c_static - base.c_static);
    p.c_residual += k * (plus.c_residual - base.c_residual);
    p.eps_t_over_s += k * (plus.eps_t_over_s - base.eps_t_over_s);
    for (std::size_t i = 0; i < p.modes.size(); ++i) {
      auto& m = p.modes[i];
      const auto &mp = plus.modes[i], &mb = base.modes[i];
      m.omega += k * (mp.omega - mb.omega);
      m.kappa += k * (mp.kappa - mb.kappa);
      // p_k = gᵀφ_k: its sign is the eigenvector's, arbitrary per solve.
      m.participation = std::abs(m.participation) + k * (std::abs(mp.participation) - std::abs(mb.participation));
    }
  }
  std::vector<cd> transfer_of(const model::ModalPortModel& port, double beta, double eta,
                              const model::EffectSet& fx) const {
    const model::RayleighDamping damp{0.0, beta};
    std::vector<cd> t(kmax_ + 1);
    for (std::size_t k = 0; k <= kmax_; ++k) {
      const double w = kTwoPi * fs_ * double(k) / double(nfft_);
      const cd yt = w > 0 ? model::tube_admittance(port, damp, fx, w, eta) : cd(0.0, 0.0);
      t[k] = model::recorded_transfer(yt, fx, r1_, w);
    }
    return t;
  }

  Eigen::VectorXd invert() {
    for (std::size_t k = kmax_ + 1; k < spec_.size(); ++k) spec_[k] = 0.0;
    fft_.inverse(spec_.data(), buf_.data(), n_);
    Eigen::VectorXd r(static_cast<Eigen::Index>(idx_.size()));
    const double scale = 1.0 / double(nfft_);
    for (std::size_t i = 0; i < idx_.size(); ++i) r[static_cast<Eigen::Index>(i)] = buf_[idx_[i]] * scale;
    return r;
  }

  using Key = Eigen::Matrix<double, 5, 1>;  // the constants' coordinates, the end mass
  struct Cached {
    Key key;
    std::optional<model::ModalPortModel> port;
    unsigned long used = 0;
  };
  static Key key_of(const Eigen::VectorXd& x, double end_mass) {
    Key key;
    key << x.head<4>(), end_mass;
    return key;
  }
  Cached* cached(const Key& key) {
    for (auto& c : cache_)
      if (c.key == key) {
        c.used = ++clock_;
        return &c;
      }
    return nullptr;
  }
  // One FE port model (counted; thread-safe for distinct solvers).
  std::optional<model::ModalPortModel> build(model::ModalSolver& solver, const Key& key) {
    ++evaluations_;
    try {
      model::ModalOptions mo = modal_;
      mo.end_mass_fraction = key[4];
      Eigen::VectorXd x = Eigen::VectorXd::Zero(kParams);
      x.head<4>() = key.head<4>();
      auto port = solver.port_model(cls_.e_form(co_.params(x)), mo);
      if (port.converged) return port;
    } catch (const std::exception&) {
    }
    return std::nullopt;
  }
  const model::ModalPortModel* insert(const Key& key, std::optional<model::ModalPortModel> port) {
    Cached* slot = nullptr;
    if (cache_.size() < kCache) {
      slot = &cache_.emplace_back();
    } else {
      slot = &*std::min_element(cache_.begin(), cache_.end(),
                                [](const Cached& a, const Cached& b) { return a.used < b.used; });
    }
    slot->key = key;
    slot->port = std::move(port);
    slot->used = ++clock_;
    return slot->port ? &*slot->port : nullptr;
  }

  model::ModalSolver& solver_;
  std::unique_ptr<model::ModalSolver> solver2_;  // prefetch's second thread (built on first use)
  int threads_ = 1;
  const MaterialClass& cls_;
  Coordinates5 co_;
  model::ModalOptions modal_;
  double r1_;
  model::EffectSet fx_;
  std::function<void(model::EffectSet&, double)> free_;
  double fs_;
  std::size_t n_, nfft_;
  dsp::RealFft fft_;
  std::size_t kmax_ = 0, decim_ = 1;
  std::vector<cd> l_, lv1_, ly_, spec_;
  std::vector<double> buf_;
  std::vector<std::size_t> idx_;
  std::atomic<int> evaluations_{0};
  static constexpr std::size_t kCache = 16;  // a grid's nine models, an exact Jacobian's five and the trials
  static constexpr double kTangentReach = 0.05;
  // The check of tangent_near: relative error of the prediction (a veering
  // swaps participations by tens of percent, the curvature away from one
  // moves them by well under a percent within the reach).
  static constexpr double kTangentTolerance = 0.01;        // participation
  static constexpr double kTangentOmegaTolerance = 1e-3;   // frequency
  static constexpr double kActiveCoupling = 1e-4;          // p²/(ω²C0) of a mode it looks at
  static constexpr double kScreenChange = 0.05;            // tangent_model: Σ|Δx_c|·slope_c at most
  struct Tangent {
    bool valid = false;
    Eigen::Vector4d x_ref;
    double mass = 0, h = 0;
    model::ModalPortModel base;
    std::array<model::ModalPortModel, 4> plus;
    std::array<double, 4> slope{};  // largest relative slope of an active mode's ω or |p| per unit x_c
  } tangent_;
  std::vector<Cached> cache_;
  unsigned long clock_ = 0;

 public:
  // What the optimiser leaves behind (the cached models, the tangent): each
  // scanned effect starts from the optimum's, so its answer does not depend on
  // the order of the scan or the thread it runs on.
  struct State {
    std::vector<Cached> cache;
    Tangent tangent;
    unsigned long clock = 0;
  };
  State state() const { return {cache_, tangent_, clock_}; }
  void restore(const State& s) {
    cache_ = s.cache;
    tangent_ = s.tangent;
    clock_ = s.clock;
  }
};

// The noise of a record's filtered error at transfer t: the shots' scatter,
// else the pretrigger, else each channel's high-pass estimate.
struct RecordNoise {
  double sigma = 0;       // of the filtered, decimated error (the (averaged) record's)
  double ch1 = 0, ch2 = 0;  // white noise of each channel of the (averaged) record, volts
  double dof = 0;         // degrees of freedom of the estimate
  std::string source;
};

RecordNoise record_noise(Problem& prob, const Averaged& rec, const std::vector<cd>& t) {
  RecordNoise out;
  const std::size_t n = rec.v1.size();
  if (rec.shots >= 2) {
    double ss = 0;
    std::size_t m = 0;
    for (std::size_t k = 0; k < rec.dev1.size(); ++k) {
      const Eigen::VectorXd e = prob.deviation(t, rec.dev1[k], rec.dev2[k]);
      ss += e.squaredNorm();
      m += static_cast<std::size_t>(e.size());
    }
    out.source = "shots (" + std::to_string(rec.shots) + ")";
    out.dof = double(m) * double(rec.shots - 1) / double(rec.shots);
    // per-shot variance ss/((K−1)·M/K·…): Σ_k ‖e_k‖² = (K−1)/K·K·M·σ², the average's σ²/K
    const double var_shot = ss / (double(m) * double(rec.shots - 1) / double(rec.shots));
    double q1 = 0, q2 = 0;
    for (std::size_t k = 0; k < rec.dev1.size(); ++k)
      for (std::size_t i = 0; i < n; ++i) {
        q1 += rec.dev1[k][i] * rec.dev1[k][i];
        q2 += rec.dev2[k][i] * rec.dev2[k][i];
      }
    out.ch1 = std::sqrt(q1 / (double(n) * double(rec.shots - 1)) / double(rec.shots));
    out.ch2 = std::sqrt(q2 / (double(n) * double(rec.shots - 1)) / double(rec.shots));
    out.sigma = std::sqrt(var_shot / double(rec.shots));
    return out;
  }
  double s1 = 0, s2 = 0;
  if (rec.pretrigger >= 64 && rec.pretrigger < n) {
    for (std::size_t i = 0; i < rec.pretrigger; ++i) {
      s1 += rec.v1[i] * rec.v1[i];
      s2 += rec.v2[i] * rec.v2[i];
    }
    s1 = std::sqrt(s1 / double(rec.pretrigger - 1));
    s2 = std::sqrt(s2 / double(rec.pretrigger - 1));
    out.source = "pretrigger (" + std::to_string(rec.pretrigger) + " samples)";
    out.dof = double(rec.pretrigger - 1);
  } else {
    const Eigen::Map<const Eigen::VectorXd> a(rec.v1.data(), static_cast<Eigen::Index>(n)),
        b(rec.v2.data(), static_cast<Eigen::Index>(n));
    s1 = dsp::estimate_noise_std(a);
    s2 = dsp::estimate_noise_std(b);
    out.source = "high-pass estimate of each channel";
    // The median of |6th differences| of overlapping windows: about a fifth
    // of the samples' worth of independent information.
    out.dof = 0.2 * double(n);
  }
  out.ch1 = s1;
  out.ch2 = s2;
  out.sigma = prob.propagated_sigma(t, s1, s2);
  return out;
}

// The DAQ offsets. Removed with the pretrigger's mean, each channel keeps an
// error of σ_raw/√P, constant over the record: in the filtered error a
// component along u = L ∗ 1 (v1's offset reaches v2 through T, which is 1
// at low frequency) of variance τ² = (σ1² + σ2²)/P — correlated noise that
// white weighting would count as lack of fit. It is marginalised: the
// residual is whitened with the covariance σ²I + τ²uuᵀ (its component along
// u shrunk by 1/√(1 + τ²uᵀu/σ²)). Without a pretrigger the offsets are
// unknown (τ = ∞): the component is projected out, one degree of freedom less.
// u = L ∗ (T ∗ 0 − 1): the filtered error of a unit offset on v2 (out of line:
// GCC 12 inlining it into OffsetWhitening reports a false free-nonheap-object).
[[gnu::noinline]] Eigen::VectorXd unit_offset_response(Problem& prob, std::size_t n, const std::vector<cd>& t) {
  const std::vector<double> zero(n, 0.0), one(n, 1.0);
  return -prob.deviation(t, zero, one);
}

struct OffsetWhitening {
  Eigen::VectorXd u;
  double uu = 0;
  double shrink = 1.0;  // 1 − 1/√(1 + τ²uᵀu/σ²): the share of the u component removed
  int dof = 1;
  std::string model;
  OffsetWhitening(Problem& prob, const Averaged& rec, const std::vector<cd>& t_nominal, double sigma) {
    u = unit_offset_response(prob, rec.v1.size(), t_nominal);
    uu = u.squaredNorm();
    if (rec.pretrigger >= 16 && rec.pretrigger < rec.v1.size()) {
      double s1 = 0, s2 = 0;  // the (averaged) record's idle noise: its mean was removed
      for (std::size_t i = 0; i < rec.pretrigger; ++i) {
        s1 += rec.v1[i] * rec.v1[i];
        s2 += rec.v2[i] * rec.v2[i];
      }
      const double p = double(rec.pretrigger);
      const double tau2 = (s1 + s2) / (p - 1.0) / p;
      shrink = 1.0 - 1.0 / std::sqrt(1.0 + tau2 * uu / (sigma * sigma));
      dof = 0;
      model = "pretrigger mean removed, its error marginalised";
    } else {
      model = "unknown (no pretrigger): projected out";
    }
  }
  Eigen::VectorXd operator()(Eigen::VectorXd r) const {
    if (uu > 0 && shrink > 0) r -= (shrink * u.dot(r) / uu) * u;
    return r;
  }
};

// The nominal model's third electrically active short-circuit mode (Hz), or
// its highest active one when it has fewer.
double third_active_mode_hz(model::ModalSolver& solver, const MaterialClass& cls,
                            const TubeParams& p, const model::ModalOptions& modal) {
  const auto port = solver.port_model(cls.e_form(p), modal);
  double f = 0;
  int seen = 0;
  for (const auto& m : port.modes) {
    if (m.residual || !m.symmetric) continue;
    const double coupling = m.participation * m.participation / (m.omega * m.omega * port.c_clamped);
    if (coupling < modal.active_coupling) continue;
    f = m.omega / kTwoPi;
    if (++seen == 3) break;
  }
  if (!(f > 0)) throw std::runtime_error("the nominal model has no electrically active mode");
  return f;
}

struct SpectralTest {
  double log10_p = 0;  // Bonferroni-corrected, of the most significant window
  double f_lo = 0, f_hi = 0, excess = 1;
  int windows = 0;
};

// Lack of fit concentrated in frequency: the residual's periodogram over its
// expected noise shape, scaled by its own median (robust to the noise level's
// error), summed over windows of 1..64 bins; the window least likely under
// noise alone (log_gamma_tail, update/residual_regions.hpp), its chance
// multiplied by the number of windows tried.
SpectralTest spectral_lack_of_fit(const Eigen::VectorXd& r, const Eigen::VectorXd& shape, double bin_hz) {
  SpectralTest out;
  const std::size_t m = static_cast<std::size_t>(r.size());
  if (m < 32) return out;
  dsp::RealFft fft(m);
  std::vector<cd> x(fft.bins());
  fft.forward(r.data(), m, x.data());
  const double top = shape.maxCoeff();
  std::vector<double> z;
  std::vector<std::size_t> bin;
  for (std::size_t j = 1; j + 1 < fft.bins() && j < static_cast<std::size_t>(shape.size()); ++j) {
    const double e = shape[static_cast<Eigen::Index>(j)];
    if (!(e > 1e-4 * top)) continue;  // outside the band
    z.push_back(std::norm(x[j]) / e);
    bin.push_back(j);
  }
  if (z.size() < 16) return out;
  std::vector<double> sorted = z;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<long>(sorted.size() / 2), sorted.end());
  const double scale = std::log(2.0) / sorted[sorted.size() / 2];
  for (auto& v : z) v *= scale;
  double best = 0;
  for (int w = 1; w <= 64 && static_cast<std::size_t>(w) <= z.size(); w *= 2) {
    const std::size_t step = std::max(1, w / 2);
    for (std::size_t s0 = 0; s0 + static_cast<std::size_t>(w) <= z.size(); s0 += step) {
      double sum = 0;
      for (int i = 0; i < w; ++i) sum += z[s0 + static_cast<std::size_t>(i)];
      ++out.windows;
      const double lq = log_gamma_tail(w, sum);
      if (lq < best) {
        best = lq;
        out.f_lo = double(bin[s0]) * bin_hz;
        out.f_hi = double(bin[s0 + static_cast<std::size_t>(w) - 1]) * bin_hz;
        out.excess = sum / w;
      }
    }
  }
  out.log10_p = std::min(0.0, (best + std::log(double(out.windows))) / std::log(10.0));
  return out;
}

struct LmOutcome {
  Eigen::VectorXd x;
  double cost = 0;  // ½‖r/σ‖²
  bool converged = false;
  int iterations = 0;
  std::string message;
  Eigen::VectorXd r;       // weighted residual at x
  Eigen::MatrixXd j, jtj;  // at the answer (the runs that need them, see finish)
};

// The optimiser on one Problem: the weighted residual, its Jacobian, LM and
// the exact J at an answer. The scan of the catalogue's effects runs one per
// thread, each on its own Problem (Problem::fork).
class Fitter {
 public:
  Fitter(Problem& prob, const OffsetWhitening& whiten, const double& sigma, const OeOptions& opt, double dof_fit)
      : prob(prob), whiten(whiten), sigma(sigma), opt(opt), dof_fit(dof_fit) {}

    std::optional<Eigen::VectorXd> weighted(const Eigen::VectorXd& x) {
      auto r = prob.residual(x);
      if (!r) return std::nullopt;
      *r = whiten(std::move(*r)) / sigma;
      if (!r->allFinite()) return std::nullopt;
      return r;
    }
    // Columns from `first` on (the others kept as they are in j). The
    // constants' columns through the port models' tangent near the last exact
    // Jacobian (Problem::set_tangent), unless `exact`.
    bool jacobian(const Eigen::VectorXd& x, const Eigen::VectorXd& r0, Eigen::MatrixXd& j, int first = 0,
                  bool exact = false) {
      const auto np = static_cast<int>(x.size());  // 5, or 6 with a free effect (scan_effects)
      if (j.rows() != r0.size() || j.cols() != np) {
        j.resize(r0.size(), np);
        first = 0;
      }
      const bool tangent = !exact && first < 4 && prob.tangent_near(x);
      {  // the columns' port models at once (the constants' unless through the tangent)
        std::vector<std::pair<Eigen::VectorXd, double>> points;
        for (int c = first; c < np; ++c) {
          if (c < 4 && tangent) continue;
          Eigen::VectorXd xp = x;
          xp[c] += c >= 4 ? 1e-4 : 1e-6;
          points.emplace_back(xp, prob.effects_at(xp).mass_loading);
        }
        if (points.size() > 1) prob.prefetch(points);
      }
      for (int c = first; c < np; ++c) {
        const double h = c >= 4 ? 1e-4 : 1e-6;
        if (c < 4 && tangent) {
          if (const auto tt = prob.tangent_transfer(x, c, h)) {
            const Eigen::VectorXd rt = whiten(prob.residual_of(*tt)) / sigma;
            if (rt.allFinite()) {
              j.col(c) = (rt - r0) / h;
              continue;
            }
          }
        }
        Eigen::VectorXd xp = x;
        xp[c] += h;
        auto rp = weighted(xp);
        if (!rp) {
          xp[c] = x[c] - h;  // the other side
          rp = weighted(xp);
          if (!rp) return false;
          j.col(c) = (r0 - *rp) / h;
        } else {
          j.col(c) = (*rp - r0) / h;
        }
      }
      if (first == 0 && !tangent) prob.set_tangent(x, 1e-6);
      return true;
    }
    // ½‖r/σ‖² at x on the port models' tangent anchored at `anchor`
    // (Problem::tangent_model), NaN away from it.
    double tangent_cost(const Eigen::VectorXd& anchor, const Eigen::VectorXd& x) {
      const auto t = prob.tangent_model(anchor, x);
      if (!t) return NAN;
      const Eigen::VectorXd r = whiten(prob.residual_of(*t)) / sigma;
      return r.allFinite() ? 0.5 * r.squaredNorm() : NAN;
    }
    // LM from x. A later start (`lead`: the optimum of the first) stops early
    // once it is inside the lead's optimum (ΔxᵀJᵀJΔx < 9 at no lower cost: it
    // would converge there, and no constant differs by 3 of its statistical
    // sigmas, so the honesty check's 3-sigma test below cannot fire) or once it
    // stalls far above it (its cost gap to the lead above max(50, 10·s²) and
    // shrinking by less than a tenth per iteration: a local optimum the data
    // reject, which the honesty check below ignores anyway).
    // `j0`: the Jacobian at x when the caller has it (an effect scanned from the
    // optimum: the five's columns there are the optimum's), saving its models.
    // `freeze_material`: with j0, the four material columns stay j0's (an
    // effect scanned from the optimum moves the constants by a fraction of their
    // sigmas: their columns barely change, and each costs an FE port model);
    // β's and the effect's are recomputed (no new model). finish() computes the
    // exact J at the answer for the covariance.
    LmOutcome levenberg_marquardt(Eigen::VectorXd x, const LmOutcome* lead, const Eigen::MatrixXd* j0 = nullptr,
                                  bool freeze_material = false) {
      LmOutcome o;
      auto r = weighted(x);
      if (!r) {
        o.message = "the start cannot be simulated";
        o.cost = INFINITY;
        o.x = x;
        return o;
      }
      double cost = 0.5 * r->squaredNorm();
      double mu = 1e-3, last_drop = INFINITY;
      // J by forward differences at every iterate: four FE port models (β's
      // column reuses the cached one), or none near the last exact J (the
      // port models' tangent, Problem::set_tangent). Broyden's rank-one updates
      // instead were measured on the corpus: fewer models on the first start,
      // but later starts crawl and can look stalled where the exact J joins the
      // best optimum.
      Eigen::MatrixXd j;
      // An iteration that finds no lower cost (its J perhaps through the
      // tangent or j0's frozen columns, its trials screened) runs again on the
      // exact J, unscreened, before the run gives up.
      bool strict = false;
      for (int it = 1; it <= opt.max_iterations; ++it) {
        o.iterations = it;
        const double mu_it = mu;
        int exact_tries = 0;  // none: every try was refused by the tangent's screen
        const bool have_j0 = j0 && j0->rows() == r->size() && j0->cols() == x.size();
        bool j_ok = true;
        if (strict) {
          j_ok = jacobian(x, *r, j, 0, true);
        } else if (it == 1 && have_j0) {
          j = *j0;
        } else if (freeze_material && have_j0) {
          j = *j0;
          j_ok = jacobian(x, *r, j, 4);
        } else {
          j_ok = jacobian(x, *r, j);
        }
        if (!j_ok) {
          o.message = "the model could not be simulated near the estimate";
          break;
        }
        const Eigen::MatrixXd jtj = j.transpose() * j;
        const Eigen::VectorXd g = j.transpose() * *r;
        bool accepted = false, done = false;
        // A trial near x is screened on the tangent anchored at x first (its
        // model exact at x, the slopes x_ref's): a step it says raises the cost
        // is rejected without an FE model; one it says lowers it is computed.
        auto screen = [&](const Eigen::VectorXd& anchor, const Eigen::VectorXd& xt) {
          return strict ? NAN : tangent_cost(anchor, xt);
        };
        for (int tries = 0; tries < 14 && !accepted; ++tries) {
          Eigen::MatrixXd a = jtj;
          for (Eigen::Index p = 0; p < a.rows(); ++p) a(p, p) += mu * std::max(jtj(p, p), 1e-300);
          Eigen::VectorXd step = a.ldlt().solve(-g);
          // Trust region: no constant moves by more than 30 % in one step.
          const double big = step.cwiseAbs().maxCoeff();
          if (big > 0.3) step *= 0.3 / big;
          const Eigen::VectorXd trial = x + step;
          if (screen(x, trial) >= cost) {
            mu *= 4.0;
            // The screen alone never ends a run (its slopes are x_ref's): the
            // exact J decides (strict, below).
            if (step.cwiseAbs().maxCoeff() < opt.step_tolerance) break;
            continue;
          }
          ++exact_tries;
          const auto rt = weighted(trial);
          const double ct = rt ? 0.5 * rt->squaredNorm() : INFINITY;
          if (ct < cost) {
            const Eigen::VectorXd x_old = x;
            x = trial;
            r = rt;
            double c_new = ct;
            // Along a curved valley (resonances sliding into place) the
            // Gauss-Newton step is far shorter than the way to the minimum: go
            // on along it, doubling, while the cost keeps falling (one model per
            // try instead of a Jacobian per step; screened as above).
            Eigen::VectorXd ext = step;
            for (int d = 0; d < 4 && mu < 1e-2; ++d) {
              ext *= 2.0;
              if (ext.cwiseAbs().maxCoeff() > 0.3) break;
              const Eigen::VectorXd xe = x_old + ext;
              if (screen(x, xe) >= c_new) break;
              const auto re = weighted(xe);
              const double ce = re ? 0.5 * re->squaredNorm() : INFINITY;
              if (!(ce < c_new)) break;
              x = xe;
              r = re;
              c_new = ce;
            }
            const double drop = cost - c_new;
            last_drop = drop;
            cost = c_new;
            mu = std::max(mu / 3.0, 1e-12);
            accepted = true;
            // The cost is ½χ²: a decrease below 1e-2 leaves the estimate
            // within ~0.15 of its sigma of the optimum.
            done = step.cwiseAbs().maxCoeff() < opt.step_tolerance || drop < opt.cost_tolerance;
          } else {
            mu *= 4.0;
            if (step.cwiseAbs().maxCoeff() < opt.step_tolerance) accepted = done = true;
          }
        }
        if (done) {
          o.converged = true;
          break;
        }
        if (!accepted) {
          if (!strict) {
            strict = true;
            if (exact_tries == 0) mu = mu_it;  // (the screen's refusals grew mu, not the data)
            --it;
            continue;
          }
          double cosine = 0;
          for (Eigen::Index p = 0; p < g.size(); ++p)
            cosine = std::max(cosine, std::abs(g[p]) / std::sqrt(jtj(p, p) * 2.0 * cost + 1e-300));
          if (cosine < 1e-4) {
            o.converged = true;
          } else {
            o.message = "no decrease of the output error (gradient cosine " + std::to_string(cosine) + ")";
          }
          break;
        }
        strict = false;
        if (lead && lead->jtj.rows() == x.size() && lead->x.size() == x.size()) {
          const Eigen::VectorXd dx = x - lead->x;
          const double gap = cost - lead->cost;
          if (gap >= 0 && dx.dot(lead->jtj * dx) < 9.0) {
            o.converged = true;
            o.message = "joined the first start's optimum";
            break;
          }
          const double s2 = std::max(1.0, 2.0 * lead->cost / dof_fit);
          if (it >= 2 && gap > std::max(50.0, 10.0 * s2) && last_drop < 0.1 * gap) {
            o.message = "stalled far above the first start's optimum";
            break;
          }
        }
      }
      if (!o.converged && o.message.empty())
        o.message = "did not converge in " + std::to_string(opt.max_iterations) + " iterations";
      o.x = x;
      o.cost = cost;
      o.r = *r;
      return o;
    }
    // J and JᵀJ at a run's answer (only the best one's are used), exact: the
    // covariances are read from it (through the tangent, an effect's sigma
    // came out up to a tenth off where it trades with epsT33).
    void finish(LmOutcome& o) {
      Eigen::MatrixXd j;
      if (o.r.size() > 0 && jacobian(o.x, o.r, j, 0, true)) {
        o.j = j;
        o.jtj = j.transpose() * j;
      }
    }

  Problem& prob;

 private:
  const OffsetWhitening& whiten;
  const double& sigma;  // the noise the residual is weighted by (re-weighed once at the answer)
  const OeOptions& opt;
  double dof_fit;
};

}  // namespace

const char* damping_name(OeDamping d) {
  return d == OeDamping::complex_constants ? "complex constants" : "rayleigh";
}

std::string damping_summary(const OeResult& r) {
  char buf[160];
  if (r.damping_model == OeDamping::complex_constants)
    std::snprintf(buf, sizeof buf, "complex constants Qm %.4g +- %.2g (1/Qm on cE)", r.qm,
                  r.qm_sigma);
  else
    std::snprintf(buf, sizeof buf, "Rayleigh beta %.4g s", r.damping.beta);
  return buf;
}

std::optional<OeDamping> parse_damping(const std::string& s) {
  if (s == "rayleigh") return OeDamping::rayleigh;
  if (s == "complex" || s == "complex constants" || s == "complex_constants")
    return OeDamping::complex_constants;
  return std::nullopt;
}

std::optional<EffectCoordinate> effect_coordinate(const std::string& name) {
  EffectCoordinate c;
  if (name == "daq_input_resistance") {  // 1/R: x·1 µS
    c.typical = 1e-6;
    c.apply = [](model::EffectSet& fx, double x) {
      const double g =
          (std::isfinite(fx.daq_input_resistance_ohm) ? 1.0 / fx.daq_input_resistance_ohm : 0.0) + 1e-6 * x;
      fx.daq_input_resistance_ohm = g != 0 ? 1.0 / g : INFINITY;
    };
    c.value = [](double x) { return 1e-6 * x; };
    return c;
  }
  // Typical sizes: the unit of the coordinate (a lead of 10 Ω, a cable of
  // 100 pF, a hard PZT's loss, a 100 ns skew, 1 % gain or R1, 1 % end mass,
  // a damping ratio of 1e-3).
  static const std::pair<const char*, std::pair<double model::EffectSet::*, double>> table[] = {
      {"series_resistance", {&model::EffectSet::series_resistance_ohm, 10.0}},
      {"parallel_capacitance", {&model::EffectSet::parallel_capacitance_f, 100e-12}},
      {"dielectric_loss", {&model::EffectSet::dielectric_loss, 0.01}},
      {"channel_skew", {&model::EffectSet::channel_skew_s, 1e-7}},
      {"channel_gain", {&model::EffectSet::channel_gain, 0.01}},
      {"r1_tolerance", {&model::EffectSet::r1_tolerance, 0.01}},
      {"mass_loading", {&model::EffectSet::mass_loading, 0.01}},
      {"mechanical_damping", {&model::EffectSet::mechanical_damping, 1e-3}},
  };
  for (const auto& [n, fe] : table) {
    if (name != n) continue;
    const auto [field, typ] = fe;
    c.typical = typ;
    c.apply = [field, typ](model::EffectSet& fx, double x) { fx.*field += typ * x; };
    c.value = [typ](double x) { return typ * x; };
    return c;
  }
  return std::nullopt;
}

OeResult fit_output_error(model::ModalSolver& solver, const MaterialClass& cls,
                          const TubeParams& nominal, const OeData& data, const OeOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  const double fs = data.sample_rate_hz;
  if (!(fs > 0) || !std::isfinite(fs)) fail("sample rate must be positive");
  data.circuit.validate();
  const Averaged rec = average(data);
  if (rec.v1.size() < 256) fail("too short: " + std::to_string(rec.v1.size()) + " samples (need 256)");
  {
    double s = 0;
    for (double v : rec.v1) s += v * v;
    if (!(s > 0)) fail("v1 is zero: the capture holds no drive");
  }

  OeResult out;
  out.original = nominal;
  out.shots_used = rec.shots;
  out.r1_rel_sigma = opt.r1_rel_sigma;
  out.cp_sigma_f = opt.cp_sigma_f;
  out.gain_rel_sigma = opt.gain_rel_sigma;
  out.skew_sigma_s = opt.skew_sigma_s;
  const bool complex_loss = opt.damping == OeDamping::complex_constants;
  if (complex_loss && !(opt.eta0 > 0 && std::isfinite(opt.eta0)))
    fail("eta0 (1/Qm to start from) must be > 0");
  Coordinates5 co{nominal, complex_loss ? opt.eta0 : opt.beta0_s, opt.damping};
  try {
    out.band_hz = opt.band_hz > 0 ? opt.band_hz
                                  : std::min(1.6 * third_active_mode_hz(solver, cls, nominal, opt.modal),
                                             fs / 8.0);
  } catch (const std::exception& e) {
    out.status = UpdateStatus::solver_failure;
    out.message = std::string("the nominal model cannot be built: ") + e.what();
    return out;
  }
  if (!(out.band_hz < fs / 4)) fail("band above a quarter of the sample rate");
  Problem prob(solver, cls, co, rec, data, out.band_hz, opt.modal);
  prob.set_threads(opt.threads);
  out.residual_samples = static_cast<int>(prob.samples());
  if (prob.samples() < 4 * kParams) fail("too few samples in the band for five parameters");

  // Noise of the filtered error (record_noise) at the nominal model's T
  // (recomputed at the answer below).
  double ch1 = 0, ch2 = 0;  // per-channel white noise of the (averaged) record, volts
  auto noise_sigma = [&](const std::vector<cd>& t) {
    const RecordNoise n = record_noise(prob, rec, t);
    out.noise_source = n.source;
    out.noise_dof = n.dof;
    ch1 = n.ch1;
    ch2 = n.ch2;
    return n.sigma;
  };
  const Eigen::VectorXd x_nominal = Eigen::VectorXd::Zero(kParams);
  const auto t_nominal = prob.transfer(x_nominal);
  if (!t_nominal) {
    out.status = UpdateStatus::solver_failure;
    out.message = "the nominal model cannot be simulated";
    return out;
  }
  double sigma = noise_sigma(*t_nominal);
  if (!(sigma > 0) || !std::isfinite(sigma)) {
    // Noise-free (synthetic) data: weigh by a tiny fraction of the signal.
    sigma = 1e-9 * std::sqrt(std::max(1e-300, [&] {
              double s = 0;
              for (double v : rec.v2) s += v * v;
              return s / double(rec.v2.size());
            }()));
    out.noise_source = "none measurable (noise-free data)";
  }

  // The DAQ offsets (OffsetWhitening).
  const OffsetWhitening whiten(prob, rec, *t_nominal, sigma);
  const int offset_dof = whiten.dof;
  out.offset_model = whiten.model;
  const double dof_fit = std::max(1.0, double(prob.samples()) - kParams - offset_dof);
  Fitter fitter(prob, whiten, sigma, opt, dof_fit);
  auto weighted = [&](const Eigen::VectorXd& x) { return fitter.weighted(x); };
  auto levenberg_marquardt = [&](const Eigen::VectorXd& x, const LmOutcome* lead,
                                 const Eigen::MatrixXd* j0 = nullptr, bool freeze_material = false) {
    return fitter.levenberg_marquardt(x, lead, j0, freeze_material);
  };
  auto finish = [&](LmOutcome& o) { fitter.finish(o); };
  // Independent tasks (the later starts, the scanned effects) on up to
  // `threads` threads: the fit's Problem and a fork of it on the second
  // solver. Each task starts from `start` (Problem::State), so its answer
  // does not depend on the thread or the order; `order` lists the longest first.
  int models_elsewhere = 0;  // FE models the forks built
  auto in_parallel = [&](const std::vector<std::size_t>& order, const Problem::State& start,
                         const std::function<void(Problem&, Fitter&, std::size_t)>& task) {
    std::atomic<std::size_t> next{0};
    std::mutex error_mutex;
    std::exception_ptr error;
    auto work = [&](Problem& p, Fitter& f) {
      for (std::size_t k = next++; k < order.size(); k = next++) {
        try {
          p.restore(start);
          task(p, f, order[k]);
        } catch (...) {
          const std::lock_guard<std::mutex> lock(error_mutex);
          if (!error) error = std::current_exception();
        }
      }
    };
    if (prob.threads() > 1 && order.size() > 1) {
      Problem other(prob, prob.second_solver());
      Fitter other_fit(other, whiten, sigma, opt, dof_fit);
      const int threads = prob.threads();
      prob.set_threads(1);  // (the second solver is the other thread's now)
      std::thread t([&] { work(other, other_fit); });
      work(prob, fitter);
      t.join();
      prob.set_threads(threads);
      models_elsewhere += other.evaluations();
    } else {
      work(prob, fitter);
    }
    // And the fit's Problem as the tasks found it (what its own thread's last
    // task left would differ with the thread count).
    prob.restore(start);
    if (error) std::rethrow_exception(error);
  };

  // Coarse stage: the 3 × 3 grid over YE11 and nu12.
  struct Start {
    Eigen::VectorXd x;
    double cost;
  };
  std::vector<Start> grid;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b) {
      Eigen::VectorXd x = Eigen::VectorXd::Zero(kParams);
      x[0] = std::log1p(a * opt.grid_span_ye11);
      x[1] = b * opt.grid_span_nu12;
      grid.push_back({x, INFINITY});
    }
  {
    std::vector<std::pair<Eigen::VectorXd, double>> points;
    for (const auto& g : grid) points.emplace_back(g.x, prob.effects().mass_loading);
    prob.prefetch(points);
  }
  for (auto& g : grid) {
    const auto r = weighted(g.x);
    g.cost = r ? 0.5 * r->squaredNorm() : INFINITY;
  }
  std::sort(grid.begin(), grid.end(), [](const Start& a, const Start& b) { return a.cost < b.cost; });
  out.starts = static_cast<int>(grid.size());
  std::vector<LmOutcome> runs;
  runs.reserve(static_cast<std::size_t>(std::max(1, opt.refine)));
  // The best start first; the later ones (measured against its optimum: the
  // lead test) side by side.
  std::size_t n_starts = 0;
  while (n_starts < std::min<std::size_t>(static_cast<std::size_t>(std::max(0, opt.refine)), grid.size()) &&
         std::isfinite(grid[n_starts].cost))
    ++n_starts;
  if (n_starts > 0) {
    runs.push_back(levenberg_marquardt(grid[0].x, nullptr));
    finish(runs.front());  // the later starts measure against its metric
    std::vector<LmOutcome> later(n_starts - 1);
    std::vector<std::size_t> order(later.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    in_parallel(order, prob.state(), [&](Problem&, Fitter& f, std::size_t k) {
      later[k] = f.levenberg_marquardt(grid[k + 1].x, &runs.front());
    });
    for (auto& o : later) runs.push_back(std::move(o));
    for (const auto& o : runs) out.iterations += o.iterations;
  }
  std::sort(runs.begin(), runs.end(), [](const LmOutcome& a, const LmOutcome& b) { return a.cost < b.cost; });
  if (!runs.empty() && runs.front().jtj.rows() != kParams) finish(runs.front());
  out.evaluations = prob.evaluations() + models_elsewhere;
  if (runs.empty() || !std::isfinite(runs.front().cost)) {
    out.status = UpdateStatus::solver_failure;
    out.message = "no start of the output-error fit could be simulated";
    return out;
  }
  const LmOutcome& best = runs.front();
  for (const auto& r : runs) {
    out.optima.push_back(co.params(r.x));
    out.optima_cost.push_back(r.cost);
  }
  out.updated = co.params(best.x);
  out.damping = {0.0, co.beta(best.x)};
  out.damping_model = opt.damping;
  out.eta = co.eta(best.x);
  out.effect_set = prob.effects();

  // Noise at the answer, χ², covariance.
  const auto t_best = prob.transfer(best.x);
  if (t_best) {
    const double s = noise_sigma(*t_best);
    if (s > 0 && std::isfinite(s) && out.noise_source.rfind("none", 0) != 0) {
      // Re-weigh the cost and Jacobian to the noise at the answer.
      const double f = sigma / s;
      sigma = s;
      for (auto& r : runs) {
        r.cost *= f * f;
        r.jtj *= f * f;
        r.j *= f;
      }
    }
  }
  const int m = out.residual_samples;
  const double dof = std::max(1, m - kParams - offset_dof);
  out.noise_rms_v = sigma;
  out.chi2_per_dof = 2.0 * best.cost / dof;
  out.residual_rms_v = sigma * std::sqrt(2.0 * best.cost / m);
  const double s2 = std::max(1.0, out.chi2_per_dof);
  Eigen::MatrixXd cov = Eigen::MatrixXd::Constant(kParams, kParams, NAN);
  if (best.jtj.rows() == kParams) {
    Eigen::FullPivLU<Eigen::MatrixXd> lu(best.jtj);
    if (lu.isInvertible()) cov = s2 * lu.inverse();
  }
  const Eigen::VectorXd sx_stat = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  // Relative to the answer: nu12's coordinate is relative to the nominal.
  auto relative_to_answer = [&](Eigen::MatrixXd c) {
    const double k = nominal.nu12 / out.updated.nu12;
    if (c.rows() > 1) {
      c.row(1) *= k;
      c.col(1) *= k;
    }
    return c;
  };
  out.covariance_rel = relative_to_answer(cov);
  // Type-B part: the constants' shift per unit error of each chain quantity.
  if (t_best && best.jtj.rows() == kParams && cov.allFinite()) {
    const Eigen::MatrixXd& jb = best.j;  // weighted J at the answer
    const bool have_j = jb.rows() == out.residual_samples && jb.cols() == kParams;
    const Eigen::VectorXd r0 = prob.residual_of(*t_best);
    auto shifted = [&](double model::EffectSet::*field, double by) {
      model::EffectSet fx = prob.effects();
      fx.*field += by;
      return fx;
    };
    const std::pair<model::EffectSet, double> chain[] = {
        {shifted(&model::EffectSet::r1_tolerance, 1e-4), opt.r1_rel_sigma / 1e-4},
        {shifted(&model::EffectSet::parallel_capacitance_f, 1e-12), opt.cp_sigma_f / 1e-12},
        {shifted(&model::EffectSet::channel_gain, 1e-4), opt.gain_rel_sigma / 1e-4},
        {shifted(&model::EffectSet::channel_skew_s, 1e-9), opt.skew_sigma_s / 1e-9},
    };
    if (have_j) {
      const Eigen::MatrixXd jtj = jb.transpose() * jb;
      const auto ldlt = jtj.ldlt();
      for (const auto& [b, scale] : chain) {
        if (!(scale > 0)) continue;
        const auto tb = prob.transfer(best.x, b);
        if (!tb) continue;
        const Eigen::VectorXd drb = whiten(prob.residual_of(*tb) - r0) / sigma;  // ∂r/∂b·δb, weighted
        const Eigen::VectorXd dx = -ldlt.solve(jb.transpose() * drb) * scale;  // shift per 1 sigma of b
        if (dx.allFinite()) cov += dx * dx.transpose();
      }
    }
  }
  Eigen::VectorXd sx = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  // Lack of fit: χ²/ν beyond what the noise estimate's own scatter allows.
  out.chi2_limit = 1.0 + opt.lack_of_fit_z *
                             std::sqrt(2.0 / dof + (out.noise_dof > 0 ? 2.0 / out.noise_dof : 0.0));
  out.lack_of_fit = out.chi2_per_dof > out.chi2_limit;
  // … or concentrated in frequency, where the global χ² dilutes it among
  // thousands of noise samples (an end mass shifting a few modes).
  if (t_best && best.r.size() > 0) {
    const auto st = spectral_lack_of_fit(best.r, prob.residual_psd(*t_best, ch1, ch2), prob.residual_bin_hz());
    out.band_log10_p = st.log10_p;
    out.band_excess = st.excess;
    out.band_lo_hz = st.f_lo;
    out.band_hi_hz = st.f_hi;
    out.band_windows = st.windows;
    out.lack_of_fit = out.lack_of_fit || st.log10_p < std::log10(opt.lack_of_fit_p);
  }
  if (out.lack_of_fit && t_best)
    if (const auto rs = prob.residual_spectrum(best.x, ch1, ch2)) out.regions = residual_regions(*rs, 2, opt.lack_of_fit_p);
  out.correlation = Eigen::MatrixXd::Identity(kParams, kParams);
  for (int a = 0; a < kParams; ++a)
    for (int b = 0; b < kParams; ++b)
      if (a != b) out.correlation(a, b) = cov(a, b) / (sx[a] * sx[b]);
  out.corr_nu12_d31 = out.correlation(1, 2);

  const TubeParams& u = out.updated;
  const double beta = out.damping.beta;
  struct Row {
    const char* name;
    const char* unit;
    double value, sigma, nominal;
    double limit;
  };
  const Row rows[kParams] = {
      {"YE11", "Pa", u.y_e11, u.y_e11 * sx[0], nominal.y_e11, opt.identifiable_rel_sigma},
      {"nu12", "-", u.nu12, nominal.nu12 * sx[1], nominal.nu12, opt.identifiable_rel_sigma},
      {"d31", "C/N", u.d31, std::abs(u.d31) * sx[2], nominal.d31, opt.identifiable_rel_sigma},
      {"epsT33_rel", "-", u.eps_t33 / model::kEps0, u.eps_t33 / model::kEps0 * sx[3],
       nominal.eps_t33 / model::kEps0, opt.identifiable_rel_sigma},
      complex_loss ? Row{"qm_inverse", "-", out.eta, out.eta * sx[4], opt.eta0, 0.5}
                   : Row{"beta", "s", beta, beta * sx[4], opt.beta0_s, 0.5},
  };
  if (complex_loss && out.eta > 0) {
    out.qm = 1.0 / out.eta;
    out.qm_sigma = out.qm * sx[4];  // the same relative sigma (first order in ln η)
  }
  for (int i = 0; i < kParams; ++i) {
    OeParameter p;
    p.name = rows[i].name;
    p.unit = rows[i].unit;
    p.value = rows[i].value;
    p.sigma = rows[i].sigma;
    p.sigma_statistical = rows[i].sigma * sx_stat[i] / sx[i];
    p.nominal = rows[i].nominal;
    p.status = "ok";
    char buf[400];
    const double rel = std::abs(p.sigma / p.value);
    if (!std::isfinite(p.sigma)) {
      p.status = "not identifiable";
      p.reason = "singular";
      p.note = "the data do not constrain it (singular normal equations): a longer record, a chirp or "
               "more shots";
    } else if (out.lack_of_fit) {
      p.status = "not identifiable";
      p.reason = "lack of fit";
      if (out.chi2_per_dof > out.chi2_limit)
        std::snprintf(buf, sizeof buf,
                      "the model class does not explain this capture (chi2/dof %.3g, the noise alone "
                      "allows up to %.3g): an effect outside the model biases every constant; find it "
                      "(gap diagnosis) or measure the fixture (calibration shots)",
                      out.chi2_per_dof, out.chi2_limit);
      else
        std::snprintf(buf, sizeof buf,
                      "the model class does not explain this capture in %.3g-%.3g kHz (residual power "
                      "%.3g times the noise's there, a chance of 1e%.1f under noise alone; chi2/dof "
                      "%.3g overall): an effect outside the model (an end mass, a skew) biases every "
                      "constant; find it (gap diagnosis) or measure the fixture (calibration shots)",
                      out.band_lo_hz / 1e3, out.band_hi_hz / 1e3, out.band_excess, out.band_log10_p,
                      out.chi2_per_dof);
      p.note = buf;
    } else if (rel > rows[i].limit) {
      p.status = "not identifiable";
      p.reason = "sigma";
      std::snprintf(buf, sizeof buf,
                    "relative sigma %.3g %% exceeds the %.3g %% limit: more shots (sigma falls as "
                    "1/sqrt(shots)), less noise or a drive with more energy in the band would pin it",
                    100 * rel, 100 * rows[i].limit);
      p.note = buf;
    }
    // Another optimum the data cannot tell from the best (Δχ² < 4·s²) that puts
    // this constant more than 3 sigma away.
    for (std::size_t k = 1; k < runs.size() && p.status == "ok"; ++k) {
      if (2.0 * (runs[k].cost - best.cost) > 4.0 * s2) continue;
      const double dx = std::abs(runs[k].x[i] - best.x[i]);
      if (dx > 3.0 * sx_stat[i]) {
        p.status = "not identifiable";
        p.reason = "starts";
        std::snprintf(buf, sizeof buf,
                      "two starts reach equally good fits %.3g sigma apart: a chirp or a longer record "
                      "would separate them",
                      dx / sx_stat[i]);
        p.note = buf;
      }
    }
    out.parameters.push_back(p);
  }
  // An effect's LM run and how it enters (its coordinate, with the law chosen).
  struct Refit {
    std::size_t index;  // in out.effects
    std::function<void(model::EffectSet&, double)> apply;
    std::function<double(double)> value;
    double typical;
    const model::EffectInfo* info;
    LmOutcome run;
  };
  std::vector<Refit> refits;
  // The effect's numbers from its run.
  auto fill = [&](Problem& p, Fitter& f, OeEffect& e, Refit& rf) {
    LmOutcome& run = rf.run;
    f.finish(run);
    // One Gauss-Newton step on J at the answer (a run with the material
    // columns frozen stops where J₀ᵀr = 0, a fraction of a sigma from Jᵀr = 0).
    if (run.jtj.rows() == run.x.size() && run.r.size() == run.j.rows()) {
      const Eigen::VectorXd step = -run.jtj.ldlt().solve(run.j.transpose() * run.r);
      if (step.allFinite() && step.cwiseAbs().maxCoeff() < 0.3) {
        const Eigen::VectorXd xt = run.x + step;
        if (const auto rt = f.weighted(xt); rt && 0.5 * rt->squaredNorm() < run.cost) {
          run.x = xt;
          run.r = *rt;
          run.cost = 0.5 * rt->squaredNorm();
        }
      }
    }
    e.converged = run.converged;
    e.material = co.params(run.x.head(kParams));
    e.beta_s = co.beta(run.x.head(kParams));
    e.eta = co.eta(run.x.head(kParams));
    e.damping_model = opt.damping;
    e.effect_set = p.effects();
    rf.apply(e.effect_set, run.x[kParams]);
    const double dof_e = std::max(1.0, dof - 1.0);
    e.chi2_per_dof = 2.0 * run.cost / dof_e;
    e.delta_chi2 = 2.0 * (best.cost - run.cost);
    const double v = rf.value(run.x[kParams]);
    double sv = NAN;
    if (run.jtj.rows() == kParams + 1) {
      Eigen::FullPivLU<Eigen::MatrixXd> lu(run.jtj);
      if (lu.isInvertible()) {
        const Eigen::MatrixXd ce = std::max(1.0, e.chi2_per_dof) * lu.inverse();
        sv = rf.typical * std::sqrt(std::max(0.0, ce(kParams, kParams)));
        e.covariance_rel = ce;
        const double k = nominal.nu12 / e.material.nu12;
        e.covariance_rel.row(1) *= k;
        e.covariance_rel.col(1) *= k;
      }
    }
    const bool daq = e.name == "daq_input_resistance";
    if (daq) {  // conductance → resistance, σ_R = σ_G/G²
      e.value = v > 0 ? 1.0 / v : INFINITY;
      e.sigma = v > 0 ? sv / (v * v) : NAN;
    } else {
      e.value = v;
      e.sigma = sv;
    }
    const auto st = spectral_lack_of_fit(run.r, p.residual_psd(*t_best, ch1, ch2), p.residual_bin_hz());
    e.band_log10_p = st.log10_p;
    const bool physical = daq ? v > 0 : (e.value >= rf.info->lower && e.value <= rf.info->upper);
    e.significant = !e.alias && run.converged && physical &&
                    e.delta_chi2 > opt.effect_significance * std::max(1.0, e.chi2_per_dof);
    e.explains = e.significant && e.chi2_per_dof <= out.chi2_limit && st.log10_p >= std::log10(opt.lack_of_fit_p);
  };
  // The catalogue's effects, one at a time, as a sixth coordinate from the
  // optimum (effect_coordinate). Each starts from the optimum's state
  // (Problem::State) and runs on one of up to two threads — the fit's solver
  // and a second one, each with its own Problem — so its answer is the same
  // whatever thread runs it and in what order; the result lists them in the
  // catalogue's order.
  struct Scanned {
    OeEffect e;
    std::optional<Refit> rf;  // an LM run (not the linear answer)
  };
  std::vector<std::string> scan_names;
  if (best.converged && best.j.rows() != 0 && t_best)
    for (const auto& name : opt.scan_effects) {
      if (!model::find_effect(name))
        throw std::invalid_argument("scan_effects: no effect '" + name + "' in the catalogue");
      if (effect_coordinate(name)) scan_names.push_back(name);  // (else in the catalogue, not in this model)
    }
  auto scan_one = [&](Problem& p, Fitter& f, const std::string& name) {
    Scanned s;
    const model::EffectInfo* info = model::find_effect(name);
    const auto coord = effect_coordinate(name);
    const double typical = coord->typical;
    const auto& apply = coord->apply;
    const auto& value = coord->value;
    OeEffect e;
    const int models_before = p.evaluations();
    e.name = name;
    e.typical = name == "daq_input_resistance" ? 1.0 / typical : typical;
    e.unit = info->unit;
    p.free_effect(apply);
    Eigen::VectorXd x0(kParams + 1);
    x0 << best.x, 0.0;
    // Alias: the effect's column against the five's at their optimum. And
    // the score test there (Rao): the χ² drop the effect would bring to first
    // order, (j⊥ᵀr)²/‖j⊥‖², j⊥ its column beyond the five's span.
    double score = INFINITY, step_lin = 0, jperp2 = 0;
    Eigen::MatrixXd j_start;  // J at x0: the five's columns at the optimum and the effect's
    if (auto r0 = f.weighted(x0)) {
      Eigen::VectorXd xp = x0;
      xp[kParams] = 1e-4;
      if (auto rp = f.weighted(xp)) {
        const Eigen::VectorXd je = (*rp - *r0) / 1e-4;
        if (best.j.rows() == je.size()) {
          j_start.resize(je.size(), kParams + 1);
          j_start << best.j, je;
        }
        const Eigen::VectorXd c = best.j.colPivHouseholderQr().solve(je);
        const Eigen::VectorXd jperp = je - best.j * c;
        e.alias_residual = je.norm() > 0 ? jperp.norm() / je.norm() : 0.0;
        // x₆ = 1 is `typical`; the constants' coordinates are logs (nu12 relative).
        for (int i = 0; i < 4; ++i) e.bias_pct[i] = 100.0 * c[i];
        jperp2 = jperp.squaredNorm();
        e.detectability = std::sqrt(jperp2);
        if (jperp2 > 0) {
          const double g = jperp.dot(*r0);
          score = g * g / jperp2;
          step_lin = -g / jperp2;
        }
      }
    }
    e.alias = e.alias_residual < opt.alias_threshold;
    // Far below significance to first order (and not the end mass, whose
    // effect grows faster than linearly): the linear answer, no refit.
    if (!e.alias && name != "mass_loading" && score < opt.effect_significance / 4 && jperp2 > 0) {
      const double s2e = std::max(1.0, out.chi2_per_dof);
      const double v = value(step_lin), sv = typical * std::sqrt(s2e / jperp2);
      e.converged = true;
      e.linearised = true;
      e.material = out.updated;
      e.beta_s = out.damping.beta;
      e.eta = out.eta;
      e.damping_model = out.damping_model;
      e.effect_set = p.effects();
      apply(e.effect_set, step_lin);
      e.delta_chi2 = score;
      e.chi2_per_dof = (2.0 * best.cost - score) / std::max(1.0, dof - 1.0);
      e.value = name == "daq_input_resistance" ? (v > 0 ? 1.0 / v : INFINITY) : v;
      e.sigma = name == "daq_input_resistance" ? (v > 0 ? sv / (v * v) : NAN) : sv;
      e.band_log10_p = out.band_log10_p;
      e.covariance_rel = Eigen::MatrixXd::Zero(kParams + 1, kParams + 1);
      e.covariance_rel.topLeftCorner(kParams, kParams) = out.covariance_rel;
      e.covariance_rel(kParams, kParams) = s2e / jperp2;
      s.e = std::move(e);
      return s;
    }
    // An end mass moves the modes far along a curved valley the five already
    // follow part way (4 % of added mass fits as YE11 −2.8 % at χ²/ν ≈ 1):
    // from the optimum alone LM stays at none, so where the capture shows a
    // misfit it also starts at 2 % and 4 % (each evaluation an FE model).
    const Eigen::MatrixXd* j0 = j_start.size() ? &j_start : nullptr;
    // (The end mass moves the modes themselves: its runs keep the exact J.)
    LmOutcome run = f.levenberg_marquardt(x0, nullptr, j0, name != "mass_loading");
    if (!run.converged && name != "mass_loading" && std::isfinite(run.cost)) {
      // The frozen columns did not get there: on from where it stopped, exactly.
      LmOutcome exact = f.levenberg_marquardt(run.x, nullptr);
      if (exact.converged || exact.cost < run.cost) run = std::move(exact);
    }
    if (name == "mass_loading" && out.lack_of_fit) {
      // The later starts stop once inside the best one's optimum or stalled
      // far above it (levenberg_marquardt's lead test, on the six).
      f.finish(run);
      for (double start : {2.0, 4.0}) {
        Eigen::VectorXd xs = x0;
        xs[kParams] = start;
        LmOutcome other = f.levenberg_marquardt(xs, &run);
        if (other.cost < run.cost) {
          run = std::move(other);
          f.finish(run);
        }
      }
    }
    // Dielectric loss: the FE convention (a constant complex εT33) and the
    // causal constant-phase law differ by ε' falling ~1.5·tanδ per decade —
    // at 1 % noise a misfit of its own; the capture chooses.
    if (name == "dielectric_loss") {
      e.law = "frequency-independent";
      p.free_effect([apply](model::EffectSet& fx, double x) {
        apply(fx, x);
        fx.dielectric_constant_phase = true;
      });
      LmOutcome causal = f.levenberg_marquardt(x0, nullptr);  // (its effect column is another)
      if (causal.cost < run.cost) {
        run = std::move(causal);
        e.law = "constant-phase";
      } else {
        p.free_effect(apply);
      }
    }
    Refit rf{0, apply, value, typical, info, std::move(run)};
    if (e.law == "constant-phase")
      rf.apply = [apply](model::EffectSet& fx, double x) {
        apply(fx, x);
        fx.dielectric_constant_phase = true;
      };
    fill(p, f, e, rf);
    e.fe_models = p.evaluations() - models_before;
    s.e = std::move(e);
    s.rf = std::move(rf);
    return s;
  };
  {
    std::vector<Scanned> scanned(scan_names.size());
    // The longest first: an end mass (up to three LM runs, an FE model per
    // evaluation), the dielectric loss (two laws).
    auto rank = [](const std::string& n) { return n == "mass_loading" ? 0 : n == "dielectric_loss" ? 1 : 2; };
    std::vector<std::size_t> order(scan_names.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return rank(scan_names[a]) < rank(scan_names[b]); });
    in_parallel(order, prob.state(),
                [&](Problem& p, Fitter& f, std::size_t i) { scanned[i] = scan_one(p, f, scan_names[i]); });
    for (auto& s : scanned) {
      if (s.rf) {
        s.rf->index = out.effects.size();
        refits.push_back(std::move(*s.rf));
      }
      out.effects.push_back(std::move(s.e));
    }
  }
  // Under a lack of fit the five may sit in another basin (β and a shifted
  // YE11/nu12 absorbing part of the effect: a 30 Ω lead on one 2 % shot fits
  // as YE11 −3.5 %, nu12 −12 %, β ×1.8); from there the sixth coordinate
  // cannot leave it. The two most significant effects get the coarse grid
  // again, at their fitted value, and LM from the grid's best point.
  if (out.lack_of_fit) {
    std::vector<Refit*> order;
    for (auto& rf : refits)
      if (out.effects[rf.index].delta_chi2 > opt.effect_significance) order.push_back(&rf);
    std::sort(order.begin(), order.end(), [&](const Refit* a, const Refit* b) {
      return out.effects[a->index].delta_chi2 > out.effects[b->index].delta_chi2;
    });
    if (order.size() > 2) order.resize(2);
    // Each from the state after the scan, side by side (in_parallel).
    std::vector<std::size_t> tasks(order.size());
    for (std::size_t k = 0; k < tasks.size(); ++k) tasks[k] = k;
    in_parallel(tasks, prob.state(), [&](Problem& p, Fitter& f, std::size_t k) {
      Refit* rf = order[k];
      p.free_effect(rf->apply);
      const int models_before = p.evaluations();
      Eigen::VectorXd xg_best;
      double cg_best = INFINITY;
      std::vector<Eigen::VectorXd> regrid;
      std::vector<std::pair<Eigen::VectorXd, double>> points;
      for (int a = -1; a <= 1; ++a)
        for (int b = -1; b <= 1; ++b) {
          Eigen::VectorXd xg = Eigen::VectorXd::Zero(kParams + 1);
          xg[0] = std::log1p(a * opt.grid_span_ye11);
          xg[1] = b * opt.grid_span_nu12;
          xg[4] = rf->run.x[4];
          xg[kParams] = rf->run.x[kParams];
          regrid.push_back(xg);
          points.emplace_back(xg, p.effects_at(xg).mass_loading);
        }
      p.prefetch(points);
      for (const auto& xg : regrid) {
        const auto rg = f.weighted(xg);
        const double cg = rg ? 0.5 * rg->squaredNorm() : INFINITY;
        if (cg < cg_best) cg_best = cg, xg_best = xg;
      }
      if (!std::isfinite(cg_best)) return;
      // (fill() has finished the run: it leads, as the first start leads the five's later ones.)
      LmOutcome other = f.levenberg_marquardt(xg_best, &rf->run);
      if (other.cost < rf->run.cost) {
        rf->run = std::move(other);
        fill(p, f, out.effects[rf->index], *rf);  // (each task its own effect)
      }
      out.effects[rf->index].fe_models += p.evaluations() - models_before;
    });
  }
  prob.free_effect({});
  std::sort(out.effects.begin(), out.effects.end(),
            [](const OeEffect& a, const OeEffect& b) { return a.delta_chi2 > b.delta_chi2; });

  out.status = best.converged ? UpdateStatus::converged : UpdateStatus::max_iterations;
  out.message = best.converged ? "" : best.message;
  out.evaluations = prob.evaluations() + models_elsewhere;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls, const TubeParams& params,
                                  double beta_s, const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& opt, const Eigen::MatrixXd& covariance_rel,
                                  const std::string& effect) {
  return predict_output_error(solver, cls, params, OeLoss{OeDamping::rayleigh, beta_s, 0.0},
                              effects, data, band_hz, opt, covariance_rel, effect);
}

OePrediction predict_output_error(model::ModalSolver& solver, const MaterialClass& cls,
                                  const TubeParams& params, const OeLoss& loss,
                                  const model::EffectSet& effects, const OeData& data,
                                  double band_hz, const OeOptions& opt,
                                  const Eigen::MatrixXd& covariance_rel,
                                  const std::string& effect) {
  const double fs = data.sample_rate_hz;
  if (!(fs > 0) || !std::isfinite(fs)) fail("sample rate must be positive");
  data.circuit.validate();
  if (!(band_hz > 0) || !(band_hz < fs / 4)) fail("band above a quarter of the held-out capture's sample rate");
  const Averaged rec = average(data);
  if (rec.v1.size() < 256) fail("too short: " + std::to_string(rec.v1.size()) + " samples (need 256)");
  const Coordinates5 co{params, loss.model == OeDamping::complex_constants ? loss.eta : loss.beta_s,
                        loss.model};
  Problem prob(solver, cls, co, rec, data, band_hz, opt.modal);
  const Eigen::VectorXd x = Eigen::VectorXd::Zero(kParams);
  const auto t = prob.transfer(x, effects);
  if (!t) throw std::runtime_error("predict_output_error: the model cannot be simulated");
  OePrediction out;
  out.shots_used = rec.shots;
  const RecordNoise noise = record_noise(prob, rec, *t);
  double sigma = noise.sigma;
  out.noise_source = noise.source;
  out.noise_dof = noise.dof;
  if (!(sigma > 0) || !std::isfinite(sigma)) fail("the held-out capture shows no measurable noise");
  const OffsetWhitening whiten(prob, rec, *t, sigma);
  out.offset_model = whiten.model;
  const Eigen::VectorXd r = whiten(prob.residual_of(*t)) / sigma;
  out.samples = static_cast<int>(r.size());
  out.dof = std::max(1.0, double(r.size()) - whiten.dof);
  out.noise_rms_v = sigma;
  out.residual_rms_v = sigma * std::sqrt(r.squaredNorm() / double(std::max<Eigen::Index>(1, r.size())));
  double chi2 = r.squaredNorm();
  // The prediction's uncertainty: the fit's constants may sit anywhere their
  // covariance C allows. χ² = min over θ of ‖r(θ)‖² + (θ − θ̂)ᵀC⁻¹(θ − θ̂) —
  // to first order rᵀ(I + W·C·Wᵀ)⁻¹r (W the held-out Jacobian), but a fit of
  // a few-percent-noise shot has sigmas a rich held-out record does not see
  // linearly: a few Gauss-Newton steps of the penalised problem.
  const Eigen::Index np = covariance_rel.rows();
  const auto coord = effect.empty() ? std::nullopt : effect_coordinate(effect);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(kParams);  // the constants where the held-out data put them
  if ((np == kParams || (np == kParams + 1 && coord)) && covariance_rel.cols() == np && covariance_rel.allFinite()) {
    // C⁻¹ on C's positive eigenvalues (a covariance from a nearly singular
    // JᵀJ can carry rounding-negative ones; a direction C does not constrain
    // gets no penalty-free freedom: its eigenvalue is floored).
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (covariance_rel + covariance_rel.transpose()));
    const double lmax = es.eigenvalues().cwiseAbs().maxCoeff();
    const Eigen::VectorXd lam = es.eigenvalues().cwiseMax(1e-12 * lmax + 1e-300);
    const Eigen::MatrixXd cinv = es.eigenvectors() * lam.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    auto residual_at = [&](const Eigen::VectorXd& z) -> std::optional<Eigen::VectorXd> {
      model::EffectSet fx = effects;
      if (np > kParams) coord->apply(fx, z[kParams]);
      const auto tz = prob.transfer(z.head(kParams), fx);
      if (!tz) return std::nullopt;
      Eigen::VectorXd rz = whiten(prob.residual_of(*tz)) / sigma;
      if (!rz.allFinite()) return std::nullopt;
      return rz;
    };
    z = Eigen::VectorXd::Zero(np);
    Eigen::VectorXd rz = r;
    double cost = chi2;
    for (int it = 0; it < 4; ++it) {
      Eigen::MatrixXd w(rz.size(), np);
      bool ok = true;
      // The constants' columns through the port models' tangent (Problem::set_tangent).
      model::EffectSet fz = effects;
      if (np > kParams) coord->apply(fz, z[kParams]);
      const Eigen::VectorXd zm = z.head(kParams);
      const bool tangent = prob.tangent_near(zm, fz.mass_loading);
      for (Eigen::Index c = 0; c < np && ok; ++c) {
        const double h = c >= 4 ? 1e-4 : 1e-6;
        if (c < 4 && tangent)
          if (const auto tt = prob.tangent_transfer(zm, static_cast<int>(c), h, fz)) {
            const Eigen::VectorXd rt = whiten(prob.residual_of(*tt)) / sigma;
            if (rt.allFinite()) {
              w.col(c) = (rt - rz) / h;
              continue;
            }
          }
        Eigen::VectorXd zp = z;
        zp[c] += h;
        const auto rp = residual_at(zp);
        if (!rp) ok = false;
        else w.col(c) = (*rp - rz) / (zp[c] - z[c]);
      }
      if (!ok) break;
      if (!tangent) prob.set_tangent(zm, 1e-6, fz.mass_loading);
      const Eigen::VectorXd g = w.transpose() * rz + cinv * z;
      const Eigen::MatrixXd a = w.transpose() * w + cinv;
      Eigen::VectorXd step = -a.ldlt().solve(g);
      if (!step.allFinite()) break;
      bool accepted = false;
      for (int half = 0; half < 4 && !accepted; ++half, step *= 0.5) {
        const Eigen::VectorXd zt = z + step;
        const auto rt = residual_at(zt);
        if (!rt) continue;
        const double ct = rt->squaredNorm() + zt.dot(cinv * zt);
        if (ct < cost) {
          const double drop = cost - ct;
          z = zt;
          rz = *rt;
          cost = ct;
          accepted = true;
          if (drop < 1e-3 * out.dof) it = 4;  // converged (to a thousandth of χ²/ν)
        }
      }
      if (!accepted) break;
    }
    if (std::isfinite(cost) && cost >= 0) {
      chi2 = cost;
      out.prediction_uncertainty = true;
    }
  }
  if (!std::isfinite(chi2)) throw std::runtime_error("predict_output_error: the prediction is not finite");
  out.chi2_per_dof = chi2 / out.dof;
  out.chi2_limit = 1.0 + opt.lack_of_fit_z * std::sqrt(2.0 / out.dof + (out.noise_dof > 0 ? 2.0 / out.noise_dof : 0.0));
  // Where the prediction misses (issue 21): the held-out data of another
  // drive often show what the fit's own record cannot. Only the prediction
  // without an effect is located (gap_output_error.cpp reads no other).
  if (effect.empty() && out.chi2_per_dof > out.chi2_limit) {
    model::EffectSet fz = effects;
    if (z.size() > kParams && coord) coord->apply(fz, z[kParams]);
    if (const auto rs = prob.residual_spectrum(z.head(kParams), fz, noise.ch1, noise.ch2))
      out.regions = residual_regions(*rs, 2, opt.lack_of_fit_p);
  }
  return out;
}

}  // namespace piezo::update
