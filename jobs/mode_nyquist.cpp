#include "jobs/mode_nyquist.hpp"

#include <algorithm>
#include <cmath>

namespace piezo::jobs {

std::vector<ModeNyquist> mode_nyquist(const std::vector<double>& f_hz, const std::vector<std::complex<double>>& z_ohm,
                                      const dsp::ModeFiguresResult& figures, int neighbours) {
  std::vector<ModeNyquist> out;
  const auto& modes = figures.modes;
  for (std::size_t m = 0; m < modes.size(); ++m) {
    const auto& mf = modes[m];
    const auto& p = mf.fit.p;
    if (!mf.fit.converged || !(p.r1_ohm > 0) || !(mf.window_hi_hz > mf.window_lo_hz)) continue;
    ModeNyquist n;
    n.mode = static_cast<int>(m);
    n.fs_hz = 1.0 / (2.0 * M_PI * std::sqrt(p.l1_h * p.c1_f));
    for (std::size_t i = 0; i < f_hz.size() && i < z_ohm.size(); ++i) {
      if (f_hz[i] < mf.window_lo_hz || f_hz[i] > mf.window_hi_hz || z_ohm[i] == 0.0) continue;
      const std::complex<double> y = 1.0 / z_ohm[i];
      n.f_hz.push_back(f_hz[i]);
      n.g_s.push_back(y.real());
      n.b_s.push_back(y.imag());
    }
    // The fitted network: this branch and C0, and the neighbouring modes'
    // branches (the background the fit subtracted, dsp/mode_figures.hpp).
    const std::size_t lo = m >= static_cast<std::size_t>(neighbours) ? m - static_cast<std::size_t>(neighbours) : 0;
    const std::size_t hi = std::min(modes.size() - 1, m + static_cast<std::size_t>(neighbours));
    const int dense = 400;
    for (int k = 0; k <= dense; ++k) {
      const double f = mf.window_lo_hz + (mf.window_hi_hz - mf.window_lo_hz) * k / dense;
      std::complex<double> y = p.admittance(f);
      for (std::size_t o = lo; o <= hi; ++o)
        if (o != m && modes[o].fit.converged) y += modes[o].fit.p.motional_admittance(f);
      n.fit_g_s.push_back(y.real());
      n.fit_b_s.push_back(y.imag());
    }
    // Centre: 1/(2R1) + j·ωs·C0, moved by the neighbours' admittance at fs
    // (nearly constant across the mode, as C0's is).
    std::complex<double> bg = 0.0;
    for (std::size_t o = lo; o <= hi; ++o)
      if (o != m && modes[o].fit.converged) bg += modes[o].fit.p.motional_admittance(n.fs_hz);
    n.radius_s = 0.5 / p.r1_ohm;
    n.centre_g_s = n.radius_s + bg.real();
    n.centre_b_s = 2.0 * M_PI * n.fs_hz * p.c0_f + bg.imag();
    for (int k = 0; k <= 180; ++k) {
      const double t = 2.0 * M_PI * k / 180;
      n.circle_g_s.push_back(n.centre_g_s + n.radius_s * std::cos(t));
      n.circle_b_s.push_back(n.centre_b_s + n.radius_s * std::sin(t));
    }
    out.push_back(std::move(n));
  }
  return out;
}

}  // namespace piezo::jobs
