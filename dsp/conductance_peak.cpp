#include "dsp/conductance_peak.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace piezo::dsp {

namespace {

// u/G = a·v² + b·v + c through three grid points, v = (f/f_ref)² (scaled for conditioning).
struct ResonanceForm {
  double f_ref = 0, a = 0, b = 0, c = 0;
  double v(double f) const { return (f / f_ref) * (f / f_ref); }
  double f_of(double v) const { return f_ref * std::sqrt(v); }
  double h(double v) const { return (a * v + b) * v + c; }
  double g(double v) const { return v / h(v); }
  double dg_df(double f) const {  // dG/dv · dv/df
    const double vv = v(f), hv = h(vv), dh = 2 * a * vv + b;
    return (hv - vv * dh) / (hv * hv) * 2 * f / (f_ref * f_ref);
  }
};

ResonanceForm form_through(const Eigen::VectorXd& f, const Eigen::VectorXd& g, Eigen::Index i0,
                           double f_ref) {
  Eigen::Matrix3d m;
  Eigen::Vector3d rhs;
  ResonanceForm r;
  r.f_ref = f_ref;
  for (int k = 0; k < 3; ++k) {
    const double v = r.v(f[i0 + k]);
    m.row(k) << v * v, v, 1.0;
    rhs[k] = v / g[i0 + k];
  }
  const Eigen::Vector3d s = m.fullPivLu().solve(rhs);
  r.a = s[0];
  r.b = s[1];
  r.c = s[2];
  return r;
}

// The root of G_max·h(v) = 2v in the grid interval [f_lo, f_hi] (or the nearer one).
double crossing(const ResonanceForm& r, double g_max, double f_lo, double f_hi) {
  const double qa = g_max * r.a, qb = g_max * r.b - 2, qc = g_max * r.c;
  const double disc = qb * qb - 4 * qa * qc;
  if (!(disc >= 0) || qa == 0) return kNaN;
  const double sq = std::sqrt(disc);
  const double q = -0.5 * (qb + (qb >= 0 ? sq : -sq));  // stable roots
  const double roots[2] = {q / qa, qc / q};
  const double mid = 0.5 * (f_lo + f_hi);
  double best = kNaN, dist = INFINITY;
  for (double v : roots) {
    if (!(v > 0)) continue;
    const double fr = r.f_of(v);
    const double d = (fr >= f_lo && fr <= f_hi) ? 0.0 : std::abs(fr - mid);
    if (d < dist) {
      dist = d;
      best = fr;
    }
  }
  return best;
}

}  // namespace

ConductancePeak conductance_peak(const Eigen::VectorXd& f, const Eigen::VectorXd& g,
                                 const Eigen::VectorXd& g_sigma, Eigen::Index lo, Eigen::Index hi) {
  if (g.size() != f.size() || (g_sigma.size() && g_sigma.size() != f.size()))
    throw std::invalid_argument("conductance_peak: f, g and g_sigma sizes differ");
  if (lo < 0 || hi >= f.size() || hi - lo < 2)
    throw std::invalid_argument("conductance_peak: the range needs at least 3 grid points");
  ConductancePeak out;
  Eigen::Index i = lo;
  for (Eigen::Index k = lo; k <= hi; ++k)
    if (g[k] > g[i]) i = k;
  if (i == lo || i == hi) {
    out.message = "the conductance maximum lies at the edge of the mode's range";
    return out;
  }
  if (!(g[i] > 0)) {
    out.message = "no positive conductance peak";
    return out;
  }
  const auto peak = form_through(f, g, i - 1, f[i]);
  if (!(peak.a > 0 && peak.c > 0)) {
    out.message = "the conductance peak is not resonance-shaped (noise or a neighbour)";
    return out;
  }
  const double vs = std::sqrt(peak.c / peak.a);
  out.fs_hz = peak.f_of(vs);
  out.g_max_s = peak.g(vs);
  const double half = 0.5 * out.g_max_s;
  // First grid point below half power on each side; the crossing from the form
  // through the three points nearest to it.
  Eigen::Index j2 = i, j1 = i;
  while (j2 < hi && g[j2] >= half) ++j2;
  while (j1 > lo && g[j1] >= half) --j1;
  if (g[j2] >= half || g[j1] >= half) {
    out.message = "the half-power points lie outside the mode's range";
    return out;
  }
  const Eigen::Index a2 = j2 + 1 <= hi ? j2 - 1 : j2 - 2;  // {j2−1, j2, j2+1} or {j2−2, j2−1, j2}
  const Eigen::Index a1 = j1 - 1 >= lo ? j1 - 1 : j1;      // {j1−1, j1, j1+1} or {j1, j1+1, j1+2}
  const auto right = form_through(f, g, a2, f[j2]);
  const auto left = form_through(f, g, a1, f[j1]);
  out.f2_hz = crossing(right, out.g_max_s, f[j2 - 1], f[j2]);
  out.f1_hz = crossing(left, out.g_max_s, f[j1], f[j1 + 1]);
  if (!(out.f2_hz > out.f1_hz)) {
    out.message = "no consistent half-power crossing";
    return out;
  }
  out.qm = out.fs_hz / (out.f2_hz - out.f1_hz);
  out.ok = true;
  if (g_sigma.size()) {
    // δ(f2 − f1) = δG2/|G'2| + δG1/|G'1| − (δG_max/2)(1/|G'1| + 1/|G'2|), each δG
    // with the σ of the nearest grid point (first order; independent points).
    const double d1 = std::abs(left.dg_df(out.f1_hz)), d2 = std::abs(right.dg_df(out.f2_hz));
    const double s1 = g_sigma[j1], s2 = g_sigma[j2], sm = g_sigma[i];
    const double var =
        s2 * s2 / (d2 * d2) + s1 * s1 / (d1 * d1) + std::pow(0.5 * sm * (1 / d1 + 1 / d2), 2);
    out.qm_sigma = out.qm * std::sqrt(var) / (out.f2_hz - out.f1_hz);
  }
  return out;
}

}  // namespace piezo::dsp
