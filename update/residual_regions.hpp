#pragma once
// Where the output-error fit's residual stands above the noise, and what it
// looks like there (issue 21): the answer when no effect of the catalogue
// explains a gap, so that "unexplained" still tells the technician where and
// what — and never names a catalogue effect for it.
//
// Input: the residual in frequency, e(f) = L·(T·V1 − V2) (the model minus the
// data, through the fit's low-pass L) on bins about 1/T_record apart (nearly
// independent), with its variance under noise alone,
//   var(f) = n·|L|²(σ1²|T|² + σ2²)        (white noise σ1 on v1, σ2 on v2).
// If the data hold T_true = T + δT, then e = −L·V1·δT + noise.
//
// Regions: windows of 1..64 bins of z = |e|²/var (scaled by its median, as
// the fit's band test, update/output_error/lack_of_fit.cpp) whose sum is least likely
// under noise (Gamma tail, Bonferroni over all windows tried); the most
// significant first, trimmed and grown to the bins that stand out (z ≥ 2.5);
// then the next one, disjoint from it and its skirts.
//
// What it looks like: δT in the region fitted by weighted least squares with
// each of
//   level / phase    δT = a·T, a complex (a real: gain, imaginary: phase);
//   phase slope      δT = −jωτ·T (a delay);
//   extra resonance  δT = (∂T/∂Y)·δY,  δY = jωC_b / (1 − ω²/ω_b² + jω/(ω_b·Q)):
//                    a series R-L-C branch across the transducer (a pole pair
//                    the model lacks: a mounting or fixture resonance, a mode
//                    an electrode defect makes active), C_b ≥ 0, on a grid of
//                    ω_b over the region and Q from 2 to 5000, then refined;
// the one that removes most of the region's χ² (each parameter charged 2, as
// Akaike) names the kind, if it removes at least half of the region's excess
// over the noise; else "broadband". For the resonance, the effective coupling
// of the branch k_eff² = C_b/(C_b + C) with C the transducer's capacitance
// there (IEEE 176: k_eff² = (fp² − fs²)/fp² of the branch and its shunt).
#include "dsp/signal_stats.hpp"
#include <complex>
#include <optional>
#include <string>
#include <vector>

namespace piezo::update {

struct ResidualSpectrum {
  std::vector<double> f_hz;
  std::vector<std::complex<double>> e;       // L·(T·V1 − V2)
  std::vector<std::complex<double>> lv1;     // L·V1
  std::vector<std::complex<double>> t;       // the model's recorded v2/v1
  std::vector<std::complex<double>> dt_dy;   // ∂T/∂Y of the transducer's admittance
  std::vector<std::complex<double>> y_tube;  // the model's transducer admittance (S)
  std::vector<double> var;                   // E|e|² under noise alone
  std::size_t size() const { return f_hz.size(); }
};

struct ExtraResonance {
  double f_hz = 0;       // the branch's series resonance
  double q = 0;
  // A resonance narrower than 3 bins of the record (f/Q < 3/T_record) has
  // its width set by the record, not by its damping: Q is then only known to
  // exceed q_min = f·T_record/3 (q holds the fit, not to be quoted).
  bool q_resolved = true;
  double q_min = 0;
  double c_f = 0;        // motional capacitance C_b
  double k_eff = 0;      // effective coupling of the branch against the transducer's capacitance
  double delta_chi2 = 0;  // what it removes from the region's χ²
};

struct ResidualRegion {
  double f_lo_hz = 0, f_hi_hz = 0;
  int bins = 0;
  double log10_p = 0;  // chance of the window under noise alone (Bonferroni), log10
  double excess = 1;   // residual power / expected noise power in the window
  double chi2 = 0;     // of the widened region (2 per bin), and its share of the band's excess
  double share = 0;
  std::string kind;    // "extra resonance" | "level" | "phase" | "phase slope" | "broadband"
  double level_pct = 0, phase_deg = 0, delay_s = 0;  // the level/phase and slope fits
  std::optional<ExtraResonance> resonance;  // when kind is "extra resonance"
  std::string description;  // one phrase, the same in JSON, terminal, GUI and plots
};

// ln P(X ≥ x) for X ~ Gamma(w, 1) (dsp/signal_stats.hpp).
using dsp::log_gamma_tail;

// Up to `max_regions` regions whose window has a Bonferroni chance below
// `p_threshold`, most significant first. Empty for a residual at the noise.
std::vector<ResidualRegion> residual_regions(const ResidualSpectrum& s, int max_regions = 2,
                                             double p_threshold = 1e-3);

}  // namespace piezo::update
