#pragma once
// A real bench's slow disturbances in a divider record, for the estimators
// that read samples (Prony-SS, the FFT ratio, the cross spectra; issue 33
// item 1): a slow wander (Legendre terms 1 to 3 over the record; the offset is
// the pretrigger's, as the estimators' front end removes it) and 50/60 Hz
// mains hum with its 2nd and 3rd harmonics, on channel 1
// MINUS channel 2 — the part that reaches the current (v1 − v2)/R1. (A
// baseline common to both channels is not identifiable from one record
// without a model of the drive; at low frequency it reaches Z only through v2,
// |b|/|v2| — the current's |b|/(|v1|·ωR1C) is the large error, and it is the
// one removed.)
//
// Below the first resonance the transducer is a capacitance with its loss and
// the first modes' stiffness tail, so in the lowest DFT bins of the record
//   X1 − X2 = R1·(Σ_{m≤4} (jω)^m·y_m + ω·g + jω·ln(ω/ω₁)·e)·X2 + Σ_{m≤3} (jω)^m·κ_m + D(ω)
// (bins 1 and up: the DC bin is left out) linear in the real unknowns: the
// admittance as a power series with a dielectric loss's two forms, the
// boundary terms of a record that is cut while the response still moves
// (∫₀ᵀ x' e^{−jωt} = jωX + x(T) − x(0) at the DFT's bins), and the baseline
// D = Σ c_j·DFT[P_j] + hum. Fitted by weighted least squares over the bins
// below a band of 24 cycles of the record (the baseline's content; halved
// while a resonance shows inside it: Im Y/ω of the band's top quarter more
// than 10 % off its bottom quarter's, or a (jω)⁵ term standing out), weights from each
// channel's white noise (dsp::estimate_noise_std). The baseline is kept when
// its columns lower χ² beyond chance (p below `p_value`, Bonferroni over the
// mains tried); its samples d(t), subtracted from channel 1, make v1 − v2 the
// transducer's current again (the caller decides: acq::AssessmentOptions).
#include <Eigen/Core>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct DividerBaselineOptions {
  double mains_hz = 0;     // 50 or 60 when known; 0: both tried
  int poly_degree = 3;     // Legendre terms P0..P_degree over the record
  int harmonics = 3;       // hum harmonics (when the record spans half a mains cycle)
  double p_value = 1e-3;   // the baseline's columns kept below this chance
  double cycles = 24;      // fitted band: this many cycles of the record (24/T Hz) …
  double min_cycles = 6;   // … halved down to this while a resonance shows inside it
};

struct DividerBaseline {
  bool tested = false;     // the record allowed the test (else `note` says why)
  bool found = false;      // significant (`samples`: what to subtract from channel 1)
  double delta_chi2 = 0;   // χ² the baseline's columns took
  int dof = 0;             // their number
  double log10_p = 0;      // chance of that under noise alone (Bonferroni)
  double chi2_per_dof = kNaN;  // of the fit with them (the model's adequacy in its band)
  int nu = 0;                  // its degrees of freedom
  double band_hz = 0;      // the bins fitted: 0 … band_hz
  double mains_hz = 0;     // the hum's frequency in the columns (0: none)
  double offset_v = 0;     // mean of d(t) (beyond the pretrigger means)
  double slope_v_per_s = 0, slope_sigma_v_per_s = kNaN;  // the P1 term's, σ Birge-widened
  double hum_v = kNaN;     // the fundamental's amplitude (NaN: no hum columns)
  double rms_v = 0;        // rms of d(t) over the record
  std::vector<double> samples;  // d(t) from t = 0 (pretrigger excluded), volts
  std::string note;
  // The noise power at f over the white floor the estimators' σ assume: the
  // fit's χ²/ν in its band when significantly above 1 (beyond 1 + 4·√(2/ν):
  // slow noise the baseline's columns do not hold, 1/f wander), continued
  // above the band as 1/f — 1 + (χ²/ν − 1)·band/f; 1 otherwise.
  double excess_noise(double f_hz) const;
};

// The record from its pretrigger on (as dsp::prepare_divider reads it). Never
// throws on data: a record too short, a band without bins, a fit that fails
// leave `tested` false with the reason.
DividerBaseline estimate_divider_baseline(const DividerRecord& rec, const DividerBaselineOptions& opt = {});

}  // namespace piezo::dsp
