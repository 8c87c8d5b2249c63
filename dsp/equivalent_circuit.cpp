#include "dsp/equivalent_circuit.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "dsp/circuit_adequacy.hpp"
#include "dsp/circuit_figures.hpp"
#include "numerics/levenberg_marquardt.hpp"
#include "dsp/mode_figures.hpp"

namespace piezo::dsp {

namespace {

using cd = std::complex<double>;
constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::string fmt(double v, int prec = 5) {
  std::ostringstream s;
  s.precision(prec);
  s << v;
  return s.str();
}

// Parameter layout: ln C0, ln tanδ, [ln Rs], then ln R, ln L, ln C per branch.
struct Layout {
  bool rs = false;
  std::size_t branches = 0;
  int first_branch() const { return rs ? 3 : 2; }
  int size() const { return first_branch() + 3 * static_cast<int>(branches); }
};

EquivalentCircuit circuit_of(const Layout& lay, const Eigen::VectorXd& t) {
  EquivalentCircuit c;
  c.c0_f = std::exp(t[0]);
  c.tan_delta = std::exp(t[1]);
  c.rs_ohm = lay.rs ? std::exp(t[2]) : 0.0;
  for (std::size_t k = 0; k < lay.branches; ++k) {
    const int b = lay.first_branch() + 3 * static_cast<int>(k);
    c.branches.push_back({std::exp(t[b]), std::exp(t[b + 1]), std::exp(t[b + 2])});
  }
  return c;
}

Eigen::VectorXd theta_of(const Layout& lay, const EquivalentCircuit& c) {
  Eigen::VectorXd t(lay.size());
  t[0] = std::log(c.c0_f);
  t[1] = std::log(c.tan_delta);
  if (lay.rs) t[2] = std::log(c.rs_ohm);
  for (std::size_t k = 0; k < lay.branches; ++k) {
    const int b = lay.first_branch() + 3 * static_cast<int>(k);
    t[b] = std::log(c.branches[k].r_ohm);
    t[b + 1] = std::log(c.branches[k].l_h);
    t[b + 2] = std::log(c.branches[k].c_f);
  }
  return t;
}

struct Data {
  const Eigen::VectorXd& f;
  const Eigen::VectorXcd& z;
  Eigen::VectorXd scale;  // per component (complex residuals) or of ln|Z|
  bool magnitude = false;
  Eigen::Index n() const { return f.size(); }
  Eigen::Index rows() const { return magnitude ? n() : 2 * n(); }

  Eigen::VectorXd residual(const Layout& lay, const Eigen::VectorXd& t, Eigen::MatrixXd* jac) const {
    const EquivalentCircuit c = circuit_of(lay, t);
    Eigen::VectorXd r(rows());
    if (jac) jac->resize(rows(), lay.size());
    std::vector<cd> dy(static_cast<std::size_t>(lay.size()));
    for (Eigen::Index i = 0; i < n(); ++i) {
      const double w = kTwoPi * f[i];
      const cd s(0.0, w);
      const cd y0 = s * c.c0_f * cd(1.0, -c.tan_delta);
      cd y = y0;
      for (std::size_t k = 0; k < c.branches.size(); ++k) {
        const auto& b = c.branches[k];
        const cd yb = 1.0 / (b.r_ohm + s * b.l_h + 1.0 / (s * b.c_f));
        y += yb;
        if (jac) {
          const int p = lay.first_branch() + 3 * static_cast<int>(k);
          const cd yb2 = yb * yb;
          dy[static_cast<std::size_t>(p)] = -yb2 * b.r_ohm;
          dy[static_cast<std::size_t>(p + 1)] = -yb2 * s * b.l_h;
          dy[static_cast<std::size_t>(p + 2)] = yb2 / (s * b.c_f);
        }
      }
      const cd zy = 1.0 / y;
      const cd zm = zy + c.rs_ohm;
      if (magnitude) {
        r[i] = (std::log(std::abs(zm)) - std::log(std::abs(z[i]))) / scale[i];
      } else {
        const cd e = (zm - z[i]) / scale[i];
        r[2 * i] = e.real();
        r[2 * i + 1] = e.imag();
      }
      if (!jac) continue;
      dy[0] = y0;
      dy[1] = cd(w * c.c0_f * c.tan_delta, 0.0);
      for (int p = 0; p < lay.size(); ++p) {
        cd dz;
        if (lay.rs && p == 2)
          dz = c.rs_ohm;
        else
          dz = -zy * zy * dy[static_cast<std::size_t>(p)];
        if (magnitude) {
          (*jac)(i, p) = (dz / zm).real() / scale[i];  // d ln|Z| = Re(dZ/Z)
        } else {
          (*jac)(2 * i, p) = dz.real() / scale[i];
          (*jac)(2 * i + 1, p) = dz.imag() / scale[i];
        }
      }
    }
    return r;
  }
};

struct Trial {
  Layout lay;
  Eigen::VectorXd t;
  Eigen::MatrixXd j;
  double chi2 = kNaN, bic = kNaN;
  double neff = kNaN;  // rows × (1 − ρ)/(1 + ρ), ρ the residual's lag-1 autocorrelation
  bool converged = false;
};

Trial fit_layout(const Data& d, const Layout& lay, const Eigen::VectorXd& t0, int max_iterations) {
  numerics::LmProblem pb;
  pb.residual = [&](const Eigen::VectorXd& t) -> std::optional<Eigen::VectorXd> {
    for (Eigen::Index p = 0; p < t.size(); ++p)
      if (!(std::abs(t[p]) < 700)) return std::nullopt;
    return d.residual(lay, t, nullptr);
  };
  pb.jacobian = [&](const Eigen::VectorXd& t, const Eigen::VectorXd&, Eigen::MatrixXd& j,
                    const numerics::LmJacobianCall&) {
    d.residual(lay, t, &j);
    return j.allFinite();
  };
  numerics::LmSettings s;
  s.max_iterations = max_iterations;
  s.step_tolerance = 1e-10;
  s.relative_cost_tolerance = 1e-12;
  s.max_step = 2.0;  // no element moves by more than e² in one step
  const numerics::LmRun run = numerics::levenberg_marquardt(pb, t0, s);
  Trial tr;
  tr.lay = lay;
  tr.t = run.x;
  tr.j = run.j;
  tr.converged = run.converged;
  tr.chi2 = 2.0 * run.cost;
  return tr;
}

double bic_of(double chi2, Eigen::Index rows, int params, bool weighted) {
  const double n = static_cast<double>(rows);
  if (weighted) return chi2 + params * std::log(n);
  // Relative weights: the residual's own scale, floored at 1 ppm of |Z| (an
  // analyzer file prints 6-7 digits; below that, extra branches fit rounding).
  return n * std::log(std::max(chi2, n * 1e-12) / n) + params * std::log(n);
}

// A branch resonating at f0 with quality q whose conductance peak is g_peak.
CircuitBranch branch_at(double f0, double g_peak, double q) {
  CircuitBranch b;
  b.r_ohm = 1.0 / std::max(g_peak, 1e-12);
  b.l_h = q * b.r_ohm / (kTwoPi * f0);
  b.c_f = 1.0 / (std::pow(kTwoPi * f0, 2) * b.l_h);
  return b;
}

// Quality of a peak of g (samples on f) at index i: f_i over the half-height width.
double peak_q(const Eigen::VectorXd& f, const Eigen::VectorXd& g, Eigen::Index i) {
  const double half = 0.5 * g[i];
  Eigen::Index lo = i, hi = i;
  while (lo > 0 && g[lo] > half) --lo;
  while (hi + 1 < f.size() && g[hi] > half) ++hi;
  const double width = f[hi] - f[lo];
  if (!(width > 0)) return 1000.0;
  return std::clamp(f[i] / width, 3.0, 1e4);
}


// With the branches given, C0 and its loss are linear: the least-squares
// jωC0(1 − j·tanδ) to Y − ΣY_k in relative weights (1/|Y|²). Unchanged when
// that C0 is not positive.
void linear_c0(EquivalentCircuit& c, const Eigen::VectorXd& f, const Eigen::VectorXcd& z) {
  double sbb = 0, sby = 0, sgb = 0;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    const double w = kTwoPi * f[i];
    const cd s(0.0, w);
    cd y = 1.0 / z[i];
    const double wt = 1.0 / std::norm(y);
    for (const auto& b : c.branches) y -= 1.0 / (b.r_ohm + s * b.l_h + 1.0 / (s * b.c_f));
    sbb += wt * w * w;
    sby += wt * w * y.imag();
    sgb += wt * w * y.real();
  }
  const double c_lin = sby / sbb, g_lin = sgb / sbb;  // C0 and C0·tanδ
  if (c_lin > 0) {
    c.c0_f = c_lin;
    c.tan_delta = std::clamp(g_lin / c_lin, 1e-4, 0.2);
  }
}
}  // namespace

CircuitFit fit_equivalent_circuit(const Eigen::VectorXd& f, const Eigen::VectorXcd& z,
                                  const Eigen::VectorXd& z_sigma, const CircuitFitOptions& opt) {
  const Eigen::Index n = f.size();
  if (z.size() != n || (z_sigma.size() && z_sigma.size() != n))
    throw std::invalid_argument("fit_equivalent_circuit: f, z and z_sigma sizes differ");
  if (n < 8) throw std::invalid_argument("fit_equivalent_circuit: need at least 8 points");
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(f[i] > 0) || (i > 0 && !(f[i] > f[i - 1])))
      throw std::invalid_argument("fit_equivalent_circuit: frequencies must be > 0 and ascending (point " +
                                  std::to_string(i) + ")");
    if (!std::isfinite(z[i].real()) || !std::isfinite(z[i].imag()) || z[i] == 0.0)
      throw std::invalid_argument("fit_equivalent_circuit: non-finite or zero impedance at point " +
                                  std::to_string(i));
    if (z_sigma.size() && !(z_sigma[i] > 0))
      throw std::invalid_argument("fit_equivalent_circuit: z_sigma must be > 0 (point " + std::to_string(i) + ")");
  }
  CircuitFit out;
  out.points = static_cast<int>(n);
  out.weighted = z_sigma.size() > 0;
  int negative = 0;
  for (Eigen::Index i = 0; i < n; ++i) negative += z[i].real() < 0;
  out.magnitude_only = opt.magnitude_only || (opt.auto_magnitude_only && negative > n / 2);
  if (out.magnitude_only && !opt.magnitude_only)
    out.notes.push_back("Re Z < 0 at " + std::to_string(negative) + " of " + std::to_string(n) +
                        " points (not a passive part: the phase cannot be trusted): |Z| fitted alone");
  Data d{f, z, Eigen::VectorXd(n), out.magnitude_only};
  for (Eigen::Index i = 0; i < n; ++i) {
    if (out.magnitude_only)
      d.scale[i] = out.weighted ? z_sigma[i] / std::abs(z[i]) : 1.0;
    else
      d.scale[i] = out.weighted ? z_sigma[i] / std::sqrt(2.0) : std::abs(z[i]);
  }

  // Seeds: the given resonances, else the conductance peaks of the data (the
  // strongest first), each with R from its peak and Q from its width.
  Eigen::VectorXd g(n);
  for (Eigen::Index i = 0; i < n; ++i) g[i] = out.magnitude_only ? 1.0 / std::abs(z[i]) : (1.0 / z[i]).real();
  std::vector<std::pair<double, Eigen::Index>> peaks;  // (height, index)
  if (!opt.seed_fs_hz.empty()) {
    for (double fs : opt.seed_fs_hz) {
      if (!(fs > f[0] && fs < f[n - 1])) continue;
      const Eigen::Index i = std::lower_bound(f.data(), f.data() + n, fs) - f.data();
      peaks.push_back({g[i], i});
    }
  } else {
    // A branch per conductance peak of clear prominence (above 5 times the
    // data's scatter noise, the most prominent first) before the information
    // criterion prunes; a many-mode spectrum's strongest peak is never left
    // to the forward steps.
    const double noise = scatter_noise_rel(f, z, out.magnitude_only);
    for (const auto& p : prominent_conductance_peaks(f, z, out.magnitude_only, noise, 5.0, 1e-3)) {
      if (peaks.size() >= static_cast<std::size_t>(opt.max_branches)) break;
      peaks.push_back({g[p.index], p.index});
    }
    if (peaks.empty()) {
      std::vector<std::pair<double, Eigen::Index>> all;
      for (Eigen::Index i = 1; i + 1 < n; ++i)
        if (g[i] > g[i - 1] && g[i] >= g[i + 1]) all.push_back({g[i], i});
      std::sort(all.begin(), all.end(), [](auto& a, auto& b) { return a.first > b.first; });
      // The strongest first; a maximum inside a stronger one's half-power width
      // is that peak's noise, not a mode.
      for (const auto& [h, i] : all) {
        const double wi = f[i] / peak_q(f, g, i);
        bool apart = true;
        for (const auto& [h2, j] : peaks) apart &= std::abs(f[i] - f[j]) > std::max(wi, f[j] / peak_q(f, g, j));
        if (apart) peaks.push_back({h, i});
        if (peaks.size() >= static_cast<std::size_t>(opt.max_branches)) break;
      }
    }
  }
  if (peaks.size() > static_cast<std::size_t>(opt.max_branches)) peaks.resize(static_cast<std::size_t>(opt.max_branches));
  EquivalentCircuit c0;
  {
    const double w0 = kTwoPi * f[0];
    const cd y0 = 1.0 / z[0];
    c0.c0_f = out.magnitude_only ? 1.0 / (w0 * std::abs(z[0])) : std::max(y0.imag() / w0, 1e-3 / (w0 * std::abs(z[0])));
    c0.tan_delta = out.magnitude_only ? 0.01 : std::clamp(y0.real() / std::max(y0.imag(), 1e-300), 1e-4, 0.2);
  }
  for (const auto& [h, i] : peaks) c0.branches.push_back(branch_at(f[i], h, peak_q(f, g, i)));
  std::sort(c0.branches.begin(), c0.branches.end(), [](auto& a, auto& b) { return a.fs_hz() < b.fs_hz(); });
  double cb = 0;
  for (const auto& b : c0.branches) cb += b.c_f;
  if (c0.c0_f > 2 * cb) c0.c0_f -= cb;
  // A band that starts near a resonance reads an inflated capacitance at its
  // lowest point (a thickness-mode disc's sweep from 0.95 fs: 3.5 × its C0),
  // from which the fit can walk into a basin where a branch stands in for C0:
  // C0 from all the data instead.
  if (!out.magnitude_only) linear_c0(c0, f, z);

  const Eigen::Index rows = d.rows();
  auto score = [&](Trial& tr) {
    tr.bic = std::isfinite(tr.chi2) ? bic_of(tr.chi2, rows, tr.lay.size(), out.weighted) : INFINITY;
    // The residual's correlation along f: a network that is the wrong model
    // leaves structure, and n correlated points weigh as n_eff independent ones.
    const Eigen::VectorXd r = d.residual(tr.lay, tr.t, nullptr);
    double num = 0, den = 0;
    const Eigen::Index step = d.magnitude ? 1 : 2;
    for (Eigen::Index i = 0; i + step < r.size(); ++i) {
      den += r[i] * r[i];
      num += r[i] * r[i + step];
    }
    const double rho = den > 0 ? std::clamp(num / den, 0.0, 0.999) : 0.0;
    tr.neff = std::max(static_cast<double>(tr.lay.size() + 2), static_cast<double>(rows) * (1 - rho) / (1 + rho));
  };
  // Is trial a better than b? By the information criterion; with relative
  // weights (no per-point σ: the residual sets the scale) on the effective
  // number of points of the better-fitting one's residual, so that a branch
  // that only follows structure the network cannot describe (a real part's
  // wiggles, 236 × its scatter noise) is not bought with hundreds of
  // correlated points (EQCIRC3's sampleadmittance took 10 branches for one mode).
  auto better = [&](const Trial& a, const Trial& b) {
    if (out.weighted || !std::isfinite(a.neff) || !std::isfinite(b.neff)) return a.bic < b.bic;
    if (!std::isfinite(a.chi2)) return false;
    if (!std::isfinite(b.chi2)) return true;
    const double ne = a.chi2 < b.chi2 ? a.neff : b.neff;
    const double n = static_cast<double>(rows);
    auto crit = [&](const Trial& t) {
      return ne * std::log(std::max(t.chi2, n * 1e-12) / n) + t.lay.size() * std::log(ne);
    };
    return crit(a) < crit(b);
  };
  auto run = [&](const EquivalentCircuit& c, bool rs) {
    Layout lay{rs, c.branches.size()};
    EquivalentCircuit cc = c;
    if (rs && !(cc.rs_ohm > 0)) cc.rs_ohm = 1e-3 * d.z.cwiseAbs().minCoeff();
    Trial tr = fit_layout(d, lay, theta_of(lay, cc), opt.max_iterations);
    score(tr);
    return tr;
  };
  auto sorted = [](EquivalentCircuit c) {
    std::sort(c.branches.begin(), c.branches.end(), [](auto& a, auto& b) { return a.fs_hz() < b.fs_hz(); });
    return c;
  };

  // A low-Q branch larger than C0 stands in for C0 (the clamped capacitance
  // then comes out orders of magnitude small and every fp and k_eff with it):
  // never kept.
  auto absorbs_c0 = [](const EquivalentCircuit& c, std::size_t k) {
    return c.branches[k].qm() < 1.0 && c.branches[k].c_f > c.c0_f;
  };
  auto any_absorbs_c0 = [&](const EquivalentCircuit& c) {
    for (std::size_t k = 0; k < c.branches.size(); ++k)
      if (absorbs_c0(c, k)) return true;
    return false;
  };
  Trial best = run(c0, false);
  // A start stagewise: the most prominent peak's branch alone, then each next
  // peak's added where the data show it (sized by the residual conductance
  // there) and kept while the criterion falls. All seeds at once from their
  // crude sizes can end in a basin where one branch spans two modes (a
  // thickness-mode disc with its radial overtones inside fs–fp: |Z| misfit
  // 17 %); the better start by the criterion goes on.
  if (peaks.size() > 1 && opt.seed_fs_hz.empty()) {
    EquivalentCircuit cs = c0;
    cs.branches = {branch_at(f[peaks[0].second], peaks[0].first, peak_q(f, g, peaks[0].second))};
    if (!out.magnitude_only) linear_c0(cs, f, z);
    Trial st = run(cs, false);
    for (std::size_t p = 1; p < peaks.size(); ++p) {
      const Eigen::Index i = peaks[p].second;
      const EquivalentCircuit cur = circuit_of(st.lay, st.t);
      Eigen::VectorXd dg(n);
      for (Eigen::Index j = 0; j < n; ++j)
        dg[j] = out.magnitude_only ? std::abs(1.0 / std::abs(z[j]) - 1.0 / std::abs(cur.impedance(f[j])))
                                   : std::max(0.0, (1.0 / z[j] - 1.0 / cur.impedance(f[j])).real());
      if (!(dg[i] > 0)) continue;
      EquivalentCircuit more = cur;
      more.branches.push_back(branch_at(f[i], dg[i], peak_q(f, dg, i)));
      Trial tr = run(sorted(more), false);
      if (better(tr, st) && !any_absorbs_c0(circuit_of(tr.lay, tr.t))) st = tr;
    }
    if (better(st, best)) {
      out.notes.push_back("fitted stagewise from the most prominent peak (information criterion " + fmt(best.bic, 6) +
                          " with every seed at once, " + fmt(st.bic, 6) + " stagewise)");
      best = st;
    }
  }
  // A second start: the per-mode BVD fits of dsp/mode_figures (each mode with
  // the others as its background), when the phase is usable. The better start
  // by the criterion goes on.
  if (!out.magnitude_only) {
    try {
      const auto mf = mode_figures(f, z, z_sigma);
      EquivalentCircuit c1 = c0;
      c1.branches.clear();
      double cb1 = 0;
      for (const auto& m : mf.modes)
        if (std::isfinite(m.r1_ohm.value) && std::isfinite(m.l1_h.value) && std::isfinite(m.c1_f.value) &&
            m.r1_ohm.value > 0 && m.l1_h.value > 0 && m.c1_f.value > 0 &&
            c1.branches.size() < static_cast<std::size_t>(opt.max_branches)) {
          c1.branches.push_back({m.r1_ohm.value, m.l1_h.value, m.c1_f.value});
          cb1 += m.c1_f.value;
        }
      if (!c1.branches.empty()) {
        if (c1.c0_f > 2 * cb1) c1.c0_f = c0.c0_f + cb - cb1;
        Trial alt = run(sorted(c1), false);
        if (better(alt, best)) {
          out.notes.push_back("started from the per-mode BVD fits (information criterion " + fmt(best.bic, 6) +
                              " from the conductance peaks, " + fmt(alt.bic, 6) + " from them)");
          best = alt;
        }
      }
    } catch (const std::invalid_argument&) {
      // too few points or no mode found: the conductance peaks' start stands
    }
  }
  // ONE branch may stand above the data for the modes above the band (their
  // susceptance rises towards the band's top, which a constant C0 cannot
  // follow: the highest modes' fp would move by percents): the largest one
  // above; never reported as a mode. Any other branch outside the data goes.
  auto outside_at = [&](const EquivalentCircuit& c, std::size_t k) {
    const double fs = c.branches[k].fs_hz();
    if (!(fs > f[0])) return true;
    if (fs < f[n - 1]) return false;
    for (std::size_t j = 0; j < c.branches.size(); ++j)
      if (j != k && !(c.branches[j].fs_hz() < f[n - 1]) &&
          (c.branches[j].c_f > c.branches[k].c_f || (c.branches[j].c_f == c.branches[k].c_f && j < k)))
        return true;
    return false;
  };
  // Backward: drop branches that leave the band, stand in for C0, or whose removal lowers the criterion.
  for (bool changed = true; changed && best.lay.branches > 0;) {
    changed = false;
    const EquivalentCircuit cur = sorted(circuit_of(best.lay, best.t));
    for (std::size_t k = 0; k < cur.branches.size(); ++k) {
      EquivalentCircuit less = cur;
      less.branches.erase(less.branches.begin() + static_cast<std::ptrdiff_t>(k));
      const double fs = cur.branches[k].fs_hz();
      const bool outside = outside_at(cur, k), absorbing = absorbs_c0(cur, k);
      if (absorbing && !(less.c0_f > cur.branches[k].c_f)) less.c0_f += cur.branches[k].c_f;
      Trial tr = run(less, best.lay.rs);
      if (outside || absorbing || better(tr, best)) {
        out.notes.push_back("dropped the branch at " + fmt(fs) + " Hz (" +
                            (outside      ? std::string("outside the data")
                             : absorbing ? std::string("Q below 1 and larger than C0: it stood in for C0")
                                         : "information criterion " + fmt(best.bic, 6) + " -> " + fmt(tr.bic, 6)) +
                            ")");
        best = tr;
        changed = true;
        break;
      }
    }
  }
  // Forward: a branch where the residual stands out most, kept while the criterion falls.
  while (static_cast<int>(best.lay.branches) < opt.max_branches) {
    const Eigen::VectorXd r = d.residual(best.lay, best.t, nullptr);
    Eigen::VectorXd e(n);
    for (Eigen::Index i = 0; i < n; ++i) e[i] = d.magnitude ? r[i] * r[i] : r[2 * i] * r[2 * i] + r[2 * i + 1] * r[2 * i + 1];
    Eigen::VectorXd sm = e;
    for (Eigen::Index i = 0; i < n; ++i) {
      double s = 0;
      int cnt = 0;
      for (Eigen::Index j = std::max<Eigen::Index>(0, i - 2); j <= std::min(n - 1, i + 2); ++j) s += e[j], ++cnt;
      sm[i] = s / cnt;
    }
    Eigen::Index at = 0;
    sm.maxCoeff(&at);
    const EquivalentCircuit cur = circuit_of(best.lay, best.t);
    // The residual admittance there gives the new branch's size.
    Eigen::VectorXd dg(n);
    for (Eigen::Index i = 0; i < n; ++i)
      dg[i] = d.magnitude ? std::abs(1.0 / std::abs(z[i]) - 1.0 / std::abs(cur.impedance(f[i])))
                          : std::abs(1.0 / z[i] - 1.0 / cur.impedance(f[i]));
    EquivalentCircuit more = cur;
    more.branches.push_back(branch_at(f[at], dg[at], peak_q(f, dg, at)));
    Trial tr = run(sorted(more), best.lay.rs);
    if (!better(tr, best) || any_absorbs_c0(circuit_of(tr.lay, tr.t))) break;
    out.notes.push_back("added a branch at " + fmt(f[at]) + " Hz (information criterion " + fmt(best.bic, 6) + " -> " +
                        fmt(tr.bic, 6) + ")");
    best = tr;
  }
  if (opt.try_series_resistance && !best.lay.rs) {
    Trial tr = run(circuit_of(best.lay, best.t), true);
    if (better(tr, best)) {
      out.notes.push_back("series resistance kept (information criterion " + fmt(best.bic, 6) + " -> " + fmt(tr.bic, 6) + ")");
      best = tr;
    }
  }
  // Out-of-band branches that the forward steps may have placed: never a mode without data.
  for (int pass = 0; pass < 4; ++pass) {  // a refit may push another branch out
    EquivalentCircuit cur = circuit_of(best.lay, best.t);
    const auto before = cur.branches.size();
    const EquivalentCircuit was = cur;
    cur.branches.clear();
    for (std::size_t k = 0; k < was.branches.size(); ++k)
      if (!outside_at(was, k)) cur.branches.push_back(was.branches[k]);
    if (cur.branches.size() == before) break;
    out.notes.push_back(std::to_string(before - cur.branches.size()) + " branch(es) outside the data dropped");
    best = run(cur, best.lay.rs);
  }
  // Ascending fs, and the parameter vector and Jacobian in that order.
  {
    const EquivalentCircuit cur = sorted(circuit_of(best.lay, best.t));
    best.t = theta_of(best.lay, cur);
    d.residual(best.lay, best.t, &best.j);
  }
  out.converged = best.converged;
  out.circuit = circuit_of(best.lay, best.t);
  out.parameters = best.lay.size();
  out.chi2 = best.chi2;
  out.bic = best.bic;
  const double dof = static_cast<double>(rows - out.parameters);
  out.chi2_per_dof = dof > 0 ? out.chi2 / dof : kNaN;
  // Covariance of ln θ: (JᵀJ)⁺, scaled by the lack of fit (χ²/ν above 1) or, with
  // relative weights, by the residual's own scale.
  Eigen::MatrixXd cov = numerics::lm_covariance(best.j);
  const double inflate = out.weighted ? std::max(1.0, out.chi2_per_dof) : out.chi2_per_dof;
  cov *= std::isfinite(inflate) ? inflate : kNaN;

  out.modes = all_circuit_figures(out.circuit);
  {  // σ of every figure by central differences in ln θ
    const std::vector<double> v0 = circuit_figure_vector(out.modes);
    const int p = out.parameters;
    Eigen::MatrixXd dv(static_cast<Eigen::Index>(v0.size()), p);
    for (int c = 0; c < p; ++c) {
      const double h = 1e-6;
      Eigen::VectorXd tp = best.t, tm = best.t;
      tp[c] += h;
      tm[c] -= h;
      const auto vp = circuit_figure_vector(all_circuit_figures(circuit_of(best.lay, tp)));
      const auto vm = circuit_figure_vector(all_circuit_figures(circuit_of(best.lay, tm)));
      for (std::size_t i = 0; i < v0.size(); ++i)
        dv(static_cast<Eigen::Index>(i), c) = vp.size() == v0.size() && vm.size() == v0.size() ? (vp[i] - vm[i]) / (2 * h) : kNaN;
    }
    const Eigen::VectorXd var = (dv * cov * dv.transpose()).diagonal();
    auto slots = circuit_figure_slots(out.modes);
    for (std::size_t i = 0; i < slots.size(); ++i)
      if (std::isfinite(slots[i]->value) && std::isfinite(var[static_cast<Eigen::Index>(i)]))
        slots[i]->sigma = std::sqrt(std::max(0.0, var[static_cast<Eigen::Index>(i)]));
  }
  out.c0_f = {out.circuit.c0_f, out.circuit.c0_f * std::sqrt(std::max(0.0, cov(0, 0)))};
  out.tan_delta = {out.circuit.tan_delta, out.circuit.tan_delta * std::sqrt(std::max(0.0, cov(1, 1)))};
  if (best.lay.rs) out.rs_ohm = {out.circuit.rs_ohm, out.circuit.rs_ohm * std::sqrt(std::max(0.0, cov(2, 2)))};
  else out.rs_ohm = {0.0, kNaN};
  {  // C^T = C0 + Σ C_k, σ by its gradient in ln θ
    Eigen::VectorXd gct = Eigen::VectorXd::Zero(out.parameters);
    double ct = out.circuit.c0_f;
    gct[0] = out.circuit.c0_f;
    for (std::size_t k = 0; k < out.circuit.branches.size(); ++k) {
      ct += out.circuit.branches[k].c_f;
      gct[best.lay.first_branch() + 3 * static_cast<int>(k) + 2] = out.circuit.branches[k].c_f;
    }
    out.free_capacitance_f = {ct, std::sqrt(std::max(0.0, gct.dot(cov * gct)))};
  }
  // Misfits: over the band, and per mode in its window.
  double sz = 0, sa = 0, sy = 0;
  std::vector<double> mode_s(out.modes.size(), 0.0);
  std::vector<int> mode_n(out.modes.size(), 0);
  for (Eigen::Index i = 0; i < n; ++i) {
    const cd zm = out.circuit.impedance(f[i]);
    const double rel = std::norm((zm - z[i]) / z[i]);
    sz += rel;
    sa += std::pow(std::abs(zm) / std::abs(z[i]) - 1.0, 2);
    sy += std::pow(std::abs(z[i]) / std::abs(zm) - 1.0, 2);
    for (std::size_t k = 0; k < out.modes.size(); ++k)
      if (f[i] >= out.modes[k].window_lo_hz && f[i] < out.modes[k].window_hi_hz) {
        mode_s[k] += out.magnitude_only ? std::pow(std::abs(zm) / std::abs(z[i]) - 1.0, 2) : rel;
        ++mode_n[k];
      }
  }
  out.misfit_rel_rms = std::sqrt(sz / double(n));
  out.misfit_abs_rel_rms = std::sqrt(sa / double(n));
  out.misfit_admittance_abs_rel_rms = std::sqrt(sy / double(n));
  for (std::size_t k = 0; k < out.modes.size(); ++k) {
    out.modes[k].points = mode_n[k];
    out.modes[k].misfit_rel_rms = mode_n[k] ? std::sqrt(mode_s[k] / mode_n[k]) : kNaN;
  }
  // The branch above the data stands for the modes above the band: in the
  // network (C^T, the misfit), not a mode.
  if (!out.circuit.branches.empty() && !(out.circuit.branches.back().fs_hz() < f[n - 1])) {
    out.notes.push_back("one branch above the data (fs " + fmt(out.circuit.branches.back().fs_hz()) +
                        " Hz) stands for the modes above the band; not reported as a mode");
    out.modes.pop_back();
  }
  if (!out.converged) out.notes.push_back("the least-squares fit did not converge");
  AdequacyOptions ao;
  ao.max_branches = opt.max_branches;
  assess_circuit_fit(f, z, out, ao);
  return out;
}

}  // namespace piezo::dsp
