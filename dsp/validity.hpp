#pragma once
// Per-shot validity checks of repeated divider shots, for flagging bad data
// before it reaches an estimate:
//   clipping        a channel at the converter limit (signal_stats.hpp);
//   coherence       the ordinary coherence γ²(f) of v1 → v2 across the shots
//                   (cross spectra with one segment per shot, Bendat &
//                   Piersol 2010 §9.2.3), and per shot the coherence of its
//                   own v2 with the ensemble transfer applied to its own v1,
//                       c_k = |Σ_f V2_k*·H·V1_k|² / (Σ_f |V2_k|² · Σ_f |H·V1_k|²),
//                   H = the median over the shots of V2_k/V1_k: 1 for a shot that follows
//                   the others, lower for a shot with another response
//                   (a loose contact, a different device, an interference);
//   reconstruction  how well a Prony-SS model of the shot's order reproduces
//                   its samples: residual rms over the channel's noise std
//                   (≈ 1 when the model explains everything but noise).
#include <Eigen/Core>
#include <span>
#include <string>
#include <vector>

#include "dsp/impedance_types.hpp"
#include "dsp/prony_impedance.hpp"

namespace piezo::dsp {

struct ShotValidityOptions {
  double fmin_hz = 0.0, fmax_hz = 0.0;  // band of the coherence (fmax 0: fs/4)
  double min_shot_coherence = 0.98;     // c_k below: flagged "low coherence"
  double min_coherence = 0.9;           // γ²(f) below: that frequency is listed as low
  double max_reconstruction_ratio =
      3.0;  // residual/noise above: flagged "poor Prony reconstruction"
  std::size_t prony_samples =
      0;  // samples from t = 0 for the reconstruction (0: as many as opt.prep says)
};

struct ShotValidity {
  bool clipped = false;
  double coherence = kNaN;  // c_k (NaN with a single shot)
  double reconstruction_ratio =
      kNaN;                        // max over v1, v2 of residual rms / noise std (NaN: not fitted)
  std::vector<std::string> flags;  // "clipped", "low coherence", "poor Prony reconstruction"
};

struct ValidityReport {
  std::vector<ShotValidity> shots;      // one per record, in order
  Eigen::VectorXd f_hz, coherence;      // γ²(f) across the shots (empty with one shot)
  double low_coherence_fraction = 0.0;  // of the band's frequencies with γ² < min_coherence
};

// `records` are repeated shots of one drive; `prony` the estimate's options
// (its order, if set, is used for the reconstruction; else the automatic one).
ValidityReport check_shots(std::span<const DividerRecord> records,
                           const PronyImpedanceOptions& prony, const ShotValidityOptions& opt = {});

}  // namespace piezo::dsp
