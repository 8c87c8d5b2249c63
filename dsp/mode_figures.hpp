#pragma once
// The transducer engineer's per-mode figures from an impedance Z(f) on a grid
// (any estimator): for each resonance/anti-resonance pair the frequencies of
// IEEE Std 176-1987 (clause "Resonance frequencies": fs, fp of the motional
// branch; fm, fn at min |Z| and max |Z|) and EN 50324-2 (clause "Coupling
// factors", "Mechanical quality factor"), the effective coupling k_eff², Qm
// two ways, the Butterworth–Van Dyke branch R1, L1, C1 with its parallel C0
// (dsp/bvd_fit.hpp), the free capacitance C^T and tan δ at 1 kHz (EN 50324-2,
// "Free permittivity", "Dielectric dissipation factor") and the frequency
// constant N = fs·D_mean of the hoop mode.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "dsp/bvd_fit.hpp"
#include "dsp/conductance_peak.hpp"
#include "dsp/features.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct Uncertain {
  double value = kNaN;
  double sigma = kNaN;  // 1σ; NaN when unknown
};

struct ModeFigureOptions {
  // Mode search: the |Z| minima (and maxima) of find_features with these options.
  FeatureOptions features;
  // BVD fit window: [fs − w·Δf, fp + w·Δf], Δf = fs/Qm, clipped half-way to the
  // neighbouring modes (fp of the one below, fs of the one above).
  double window_bandwidths = 5.0;
  // Each mode is fitted with the other modes' fitted branches as a known
  // background admittance; repeated (Gauss–Seidel) until the parameters move
  // less than sweep_tolerance (relative) or after max_sweeps.
  bool subtract_other_modes = true;
  int max_sweeps = 8;
  // Work proportional to the grid: at most max_modes minima are fitted (the
  // lowest in frequency; a long noisy record's FFT has thousands of spurious
  // ones up high, said in a note), and a mode's background holds only its
  // `background_neighbours` nearest fitted branches on each side (farther ones
  // are nearly capacitive there and go into its C0), over its own stretch of grid.
  int max_modes = 32;
  int background_neighbours = 3;
  double sweep_tolerance = 1e-9;
  BvdFitOptions fit;
  // Free capacitance and tan δ at this frequency (EN 50324-2 measures C^T at
  // 1 kHz); below the grid, at its lowest frequency, with a note.
  double reference_hz = 1000.0;
  // Mean diameter (Di + Do)/2 for N = fs·D_mean; NaN: no frequency constant.
  double mean_diameter_m = kNaN;
  // The hoop (radial) mode's index among the modes found; −1: the most
  // strongly coupled one (largest k_eff²).
  int hoop_mode = -1;
};

struct ModeFigures {
  // |Z| extrema (IEEE 176: fm, fn), sub-grid refined, σ from z_sigma.
  Uncertain fm_hz, fn_hz;
  // Motional branch (IEEE 176): fs = 1/(2π√(L1C1)), fp = fs·√(1 + C1/C0).
  Uncertain fs_hz, fp_hz;
  Uncertain k_eff2, k_eff;      // k_eff² = (fp² − fs²)/fp² = C1/(C0 + C1) (EN 50324-2)
  Uncertain qm_branch;          // Qm = 1/(2π·fs·R1·C1)
  Uncertain qm_bandwidth;       // Qm = fs/(f2 − f1), conductance half-power points
  ConductancePeak conductance;  // fs at max G, f1, f2 (the bandwidth method's data)
  Uncertain r1_ohm, l1_h, c1_f, c0_f;
  Uncertain frequency_constant_hz_m;  // fs·D_mean (NaN without a diameter)
  BvdFit fit;                         // the fit's diagnostics (window points, residual, converged)
  double window_lo_hz = kNaN, window_hi_hz = kNaN;
  std::vector<std::string> notes;
  // "ok", or "unreliable" with the reasons (dsp/circuit_adequacy.hpp's checks
  // where the figures come from a network; the BVD fit's own otherwise).
  std::string status = "ok";
  std::vector<std::string> reasons;
};

struct ModeFiguresResult {
  std::vector<ModeFigures> modes;  // ascending fs
  Uncertain free_capacitance_f;    // C^T = Im Y/ω at reference_used_hz
  Uncertain tan_delta;             // Re Y/Im Y there
  double reference_used_hz = kNaN;
  int hoop_mode = -1;                 // index into modes, −1 when none
  Uncertain frequency_constant_hz_m;  // of the hoop mode
  int sweeps = 0;
  std::vector<std::string> notes;
};

// z_sigma: sqrt(E|δZ|²) per point (same size as f) or empty (then σ of the BVD
// parameters come from the fit residual, and the |Z|-extremum and bandwidth
// σ are NaN). Throws std::invalid_argument on sizes that differ or fewer than
// 5 points; a mode whose fit fails is kept with its notes.
ModeFiguresResult mode_figures(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                               const Eigen::VectorXd& z_sigma, const ModeFigureOptions& opt = {});

}  // namespace piezo::dsp
