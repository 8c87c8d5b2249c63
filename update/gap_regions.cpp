#include "update/gap_regions.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>
#include <string>

namespace piezo::update {

namespace {
using cd = std::complex<double>;

struct Extremum {
  double f;
  bool maximum;
};

// Resonances (minima) and anti-resonances (maxima) of |Z| of the model on a
// fine log grid, keeping only pronounced ones (≥ 1 dB against both neighbours).
std::vector<Extremum> model_extrema(const GapModel& m, const std::vector<double>& x, double f0, double f1) {
  std::vector<double> f;
  for (double v = f0; v <= f1; v *= 1.0005) f.push_back(v);
  const auto z = m.impedance(x, f);
  std::vector<double> a(z.size());
  for (std::size_t i = 0; i < z.size(); ++i) a[i] = 20 * std::log10(std::abs(z[i]));
  std::vector<std::pair<std::size_t, bool>> raw;
  for (std::size_t i = 1; i + 1 < a.size(); ++i) {
    if (a[i] < a[i - 1] && a[i] <= a[i + 1]) raw.emplace_back(i, false);
    if (a[i] > a[i - 1] && a[i] >= a[i + 1]) raw.emplace_back(i, true);
  }
  std::vector<Extremum> out;
  for (std::size_t k = 0; k < raw.size(); ++k) {
    const double here = a[raw[k].first];
    const double left = k > 0 ? a[raw[k - 1].first] : a.front();
    const double right = k + 1 < raw.size() ? a[raw[k + 1].first] : a.back();
    const double prom = raw[k].second ? std::min(here - left, here - right) : std::min(left - here, right - here);
    if (prom >= 1.0) out.push_back({f[raw[k].first], raw[k].second});
  }
  return out;
}

double damping_ratio(const GapModel& m, const std::vector<double>& x, double f) {
  const auto d = m.damping(x);
  const double w = 2 * M_PI * f;
  return d.alpha / (2 * w) + d.beta * w / 2 + m.effects(x).mechanical_damping;
}
}  // namespace

std::vector<GapRegion> gap_regions(const GapModel& m, const GapData& d, const std::vector<double>& x) {
  d.validate("gap_regions");
  const double f0 = d.f_hz.front(), f1 = d.f_hz.back();
  const auto ext = model_extrema(m, x, f0, f1);
  // Region boundaries.
  std::vector<GapRegion> regions;
  auto add = [&](std::string name, double lo, double hi) {
    if (!(hi > lo)) return;
    GapRegion g;
    g.name = std::move(name);
    g.f_lo_hz = lo;
    g.f_hi_hz = hi;
    regions.push_back(std::move(g));
  };
  int n_res = 0, n_anti = 0;
  std::vector<std::pair<double, double>> peak(ext.size());
  for (std::size_t k = 0; k < ext.size(); ++k) {
    const double h = std::max(3.0 * damping_ratio(m, x, ext[k].f) * ext[k].f, 0.005 * ext[k].f);
    double lo = ext[k].f - h, hi = ext[k].f + h;
    if (k > 0) lo = std::max(lo, 0.5 * (ext[k - 1].f + ext[k].f));
    if (k + 1 < ext.size()) hi = std::min(hi, 0.5 * (ext[k].f + ext[k + 1].f));
    peak[k] = {std::max(lo, f0), std::min(hi, f1)};
  }
  if (ext.empty()) {
    add("capacitive band", f0, f1);
  } else {
    add("capacitive band", f0, peak[0].first);
    for (std::size_t k = 0; k < ext.size(); ++k) {
      const int idx = ext[k].maximum ? ++n_anti : ++n_res;
      char buf[64];
      std::snprintf(buf, sizeof buf, "%s %d (%.1f kHz)", ext[k].maximum ? "anti-resonance" : "resonance", idx,
                    ext[k].f / 1e3);
      add(buf, peak[k].first, peak[k].second);
      if (k + 1 < ext.size()) {
        std::snprintf(buf, sizeof buf, "between %.1f and %.1f kHz", ext[k].f / 1e3, ext[k + 1].f / 1e3);
        add(buf, peak[k].second, peak[k + 1].first);
      }
    }
    add("high-frequency tail", peak.back().second, f1 * (1 + 1e-12));
  }
  // Residuals and the four shapes at every point.
  const auto r = gap_residuals(m, d, x);
  const double eps = 1e-4;
  std::vector<double> fp(d.f_hz), fm(d.f_hz);
  for (std::size_t i = 0; i < fp.size(); ++i) {
    fp[i] *= 1 + eps;
    fm[i] *= 1 - eps;
  }
  const auto zp = m.impedance(x, fp), zm = m.impedance(x, fm);
  std::vector<double> xd = x;
  xd[4] *= 1 + 1e-3;
  xd[5] *= 1 + 1e-3;
  const auto z0 = m.impedance(x, d.f_hz), zd = m.impedance(xd, d.f_hz);
  double total = 0;
  for (double v : r) total += v * v;
  for (auto& g : regions) {
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < d.size(); ++i)
      if (d.f_hz[i] >= g.f_lo_hz && d.f_hz[i] < g.f_hi_hz) idx.push_back(i);
    g.points = static_cast<int>(idx.size());
    for (std::size_t i : idx) g.chi2 += r[2 * i] * r[2 * i] + r[2 * i + 1] * r[2 * i + 1];
    g.share = total > 0 ? g.chi2 / total : 0;
    g.excess = g.chi2 - 2.0 * g.points;
    if (idx.empty()) {
      g.kind = "no data";
      continue;
    }
    const bool is_peak = g.name.rfind("resonance", 0) == 0 || g.name.rfind("anti-resonance", 0) == 0;
    const int nc = is_peak ? 4 : 2;
    Eigen::MatrixXd a(2 * idx.size(), nc);
    Eigen::VectorXd b(2 * idx.size());
    for (std::size_t q = 0; q < idx.size(); ++q) {
      const std::size_t i = idx[q];
      const double sr = d.sigma_log_mag[i], sp = d.sigma_phase[i];
      const int r0 = static_cast<int>(2 * q), r1 = r0 + 1;
      b(r0) = r[2 * i];
      b(r1) = r[2 * i + 1];
      a(r0, 0) = 1.0 / sr;  // level
      a(r1, 0) = 0;
      a(r0, 1) = 0;  // phase
      a(r1, 1) = 1.0 / sp;
      if (is_peak) {
        const cd shift = -(std::log(zp[i]) - std::log(zm[i])) / (2 * eps);  // measured = model shifted up by s
        const cd width = (std::log(zd[i]) - std::log(z0[i])) / 1e-3;       // damping ×(1 + w)
        a(r0, 2) = shift.real() / sr;
        a(r1, 2) = shift.imag() / sp;
        a(r0, 3) = width.real() / sr;
        a(r1, 3) = width.imag() / sp;
      }
    }
    const Eigen::VectorXd c = a.completeOrthogonalDecomposition().solve(b);
    g.level_db = 20.0 / std::log(10.0) * c(0);
    g.phase_deg = c(1) * 180.0 / M_PI;
    if (is_peak) {
      g.shift_pct = 100 * c(2);
      g.width_pct = 100 * c(3);
    }
    const char* names[] = {"level", "phase", "frequency shift", "peak width/height"};
    double best = 0;
    int arg = -1;
    for (int k = 0; k < nc; ++k) {
      const double explained = c(k) * c(k) * a.col(k).squaredNorm();
      if (explained > best) {
        best = explained;
        arg = k;
      }
    }
    // Within the noise (χ² of the region inside 3σ of its expectation): no kind.
    const double spread = 3.0 * std::sqrt(4.0 * g.points);
    g.kind = (g.excess < spread || arg < 0) ? "noise" : names[arg];
  }
  return regions;
}

std::vector<GapRegion> located_gap_regions(const std::vector<ResidualRegion>& regions, bool heldout) {
  std::vector<GapRegion> out;
  for (std::size_t i = 0; i < regions.size(); ++i) {
    const ResidualRegion& g = regions[i];
    GapRegion rg;
    rg.name = (heldout ? "held-out region " : "residual region ") + std::to_string(i + 1);
    rg.f_lo_hz = g.f_lo_hz;
    rg.f_hi_hz = g.f_hi_hz;
    rg.points = g.bins;
    rg.chi2 = g.chi2;
    rg.share = g.share;
    rg.excess = g.chi2 - 2.0 * g.bins;
    rg.kind = g.kind;
    rg.level_db = 20.0 * std::log10(std::max(1e-6, 1.0 + g.level_pct / 100.0));
    rg.phase_deg = g.phase_deg;
    rg.log10_p = g.log10_p;
    rg.delay_s = g.delay_s;
    rg.resonance = g.resonance;
    rg.description = g.description;
    out.push_back(rg);
  }
  return out;
}

std::string located_sentence(const std::vector<GapRegion>& regions, const std::string& lead) {
  std::string s;
  bool resonance = false;
  for (const auto& g : regions) {
    if (g.description.empty()) continue;
    s += (s.empty() ? " The " + lead + " stands above the noise in " : std::string("; and in ")) + g.description;
    resonance = resonance || g.resonance.has_value();
  }
  if (s.empty()) return s;
  s += ".";
  if (resonance)
    s += " An extra resonance is a pole pair the model lacks: a mounting or fixture resonance, or a mode an "
         "electrode defect makes electrically active.";
  return s;
}

}  // namespace piezo::update
