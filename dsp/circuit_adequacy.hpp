#pragma once
// Whether a fitted equivalent circuit (dsp/equivalent_circuit.hpp) describes
// the data, and figures that say so (issue 39 items 3–4; the rules are those of
// ../shared/honest-uncertainty.md).
//
// A file from an analyzer carries no per-point σ. The fit then uses relative
// weights and its covariance is s²(JᵀWJ)⁻¹ with s² = RSS/(n − p) (GUM JCGM 100
// §H.3): σ grows with the misfit. That alone is not enough: a network that is
// the wrong model leaves residuals with structure (a wiggle at each
// resonance), not noise, and the linearised covariance of n correlated points
// is that of far fewer. So, measured on the data:
//
//   * the noise from the data's own point-to-point scatter (the deviation of
//     each point from the line through its neighbours in ln f, robustly
//     scaled), and the fit's residual RMS in units of it;
//   * per mode window, the lag-1 autocorrelation ρ of the residual; when it is
//     significant (ρ√n > 3) the window's σ is widened by √((1 + ρ)/(1 − ρ)),
//     the effective-sample-size factor of an AR(1) residual;
//   * a systematic term from the data itself: the figure's offset from what
//     the data show directly (fs from the conductance maximum, fp from the
//     resistance maximum, fm and fn from the |Z| extrema, each by a parabola
//     through the three highest points) when that offset exceeds 3σ plus half
//     a grid step; k_eff's σ carries fs's and fp's (fm's and fn's);
//   * a status per mode: "unreliable" with the reasons — the |Z| misfit in
//     its window above 10 %; k_eff above 0.95 (above any material class:
//     PZT ceramics reach about 0.75, relaxor single crystals about 0.95); the
//     IEEE 176 and EN 50324-2 k_eff disagreeing beyond 3σ and by more than
//     0.02 for a mode whose figure of merit Qm·k² is 20 or more (below it the
//     forms differ by design); a half-power bandwidth wider than the mode's window or narrower
//     than two grid steps (Q not resolved); fs or fp outside the data; a
//     figure whose σ could not be determined; no conductance (|Z|) extremum
//     of the data near the mode; C0 absorbed into a low-Q branch; C0 or tan δ
//     outside physical bounds (C0 ≤ 0, tan δ > 0.1) or C^T disagreeing with
//     the data's low-frequency capacitance by more than 10 %;
//   * a status of the fit: "inadequate" when its |Z| misfit over the band
//     exceeds 10 % or it did not converge.
//   * the data's conductance peaks of clear prominence (at least 10 times the
//     scatter noise of G and 1 % of the band's largest G), each matched to a
//     reported mode, or a note saying why none is.
#include <Eigen/Core>
#include <vector>

#include "dsp/equivalent_circuit.hpp"

namespace piezo::dsp {

// The relative noise of sampled Z (per component of Z/|Z|; of ln|Z| when
// magnitude_only) from the data's point-to-point scatter: each point against
// the straight line in ln f through its two neighbours, normalised by that
// prediction's own noise factor √(1 + a² + b²), robust scale 1.4826·MAD;
// floored at 1e-6 (the 6–7 digits an analyzer prints). NaN below 5 points.
double scatter_noise_rel(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z, bool magnitude_only);

// A conductance peak of the data (of 1/|Z| when magnitude_only).
struct ConductanceDataPeak {
  Eigen::Index index = 0;
  double f_hz = 0;           // the grid point of the maximum
  double g_s = 0;            // G there
  double prominence_s = 0;   // above the higher of the two minima that bound it
  double half_width_hz = 0;  // half the width at half prominence
};

// Local maxima of G whose topographic prominence is at least min_noise times
// the scatter noise of G at the peak (noise_rel·|Y|) and min_share of the
// band's largest G; most prominent first.
std::vector<ConductanceDataPeak> prominent_conductance_peaks(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z,
                                                             bool magnitude_only, double noise_rel,
                                                             double min_noise = 10.0, double min_share = 0.01);

struct AdequacyOptions {
  double max_window_misfit = 0.10;  // |Z| relative RMS in a mode's window
  double max_band_misfit = 0.10;    // over the band: the fit is "inadequate"
  double max_k_eff = 0.95;          // relaxor single crystals; PZT ceramics ≈ 0.75
  double max_tan_delta = 0.1;
  double max_k_disagreement = 0.02;  // IEEE 176 vs EN 50324-2, beyond 3σ
  // Widen σ by the residual's correlation and the data's own extrema (off for
  // figures that are not the network's fit to these data: an FE model's).
  bool widen_sigma = true;
  // Check the figures against the data (misfits, the data's extrema, the grid's
  // resolution, the data's conductance peaks); off for an FE model's figures
  // shown beside a noisy estimate: plausibility checks only.
  bool data_checks = true;
  int max_branches = 12;  // the fit's limit (named in the notes of unmatched peaks)
};

// Sets fit.status/status_reasons, every mode's status/reasons/sigma_notes,
// noise_scatter_rel, residual_to_scatter, residual_lag1 and data_peaks, and
// widens σ as above. f, z: the data the network was fitted to (ascending f);
// without data_checks only f's ends are used (the band) and z may be empty.
void assess_circuit_fit(const Eigen::VectorXd& f_hz, const Eigen::VectorXcd& z, CircuitFit& fit,
                        const AdequacyOptions& opt = {});

}  // namespace piezo::dsp
