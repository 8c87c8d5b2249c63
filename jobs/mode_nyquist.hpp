#pragma once
// The admittance (Nyquist) view of each mode: the estimate's Y = 1/Z over the
// mode's BVD fit window, the fitted network there (the mode's branch, its C0
// and the neighbouring branches the fit took as background — the model the
// fit compared with), and the motional circle of the branch (IEEE Std 176:
// diameter 1/R1 through ωs·C0, centre 1/(2R1) + j·ωs·C0). Computed once per
// result (the GUI's frame loop only draws it; the replay report plots it).
#include <complex>
#include <vector>

#include "dsp/mode_figures.hpp"

namespace piezo::jobs {

struct ModeNyquist {
  int mode = 0;       // index into ModeFiguresResult::modes
  double fs_hz = 0;   // the branch's series resonance
  std::vector<double> f_hz, g_s, b_s;            // the estimate in the window
  std::vector<double> fit_g_s, fit_b_s;          // the fitted network, densely in the window
  std::vector<double> circle_g_s, circle_b_s;    // the motional circle
  double centre_g_s = 0, centre_b_s = 0, radius_s = 0;
};

// One entry per mode whose BVD fit converged (others have no circle to draw).
std::vector<ModeNyquist> mode_nyquist(const std::vector<double>& f_hz, const std::vector<std::complex<double>>& z_ohm,
                                      const dsp::ModeFiguresResult& figures,
                                      int neighbours = dsp::ModeFigureOptions{}.background_neighbours);

}  // namespace piezo::jobs
