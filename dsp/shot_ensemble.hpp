#pragma once
// Z(f) from repeated shots of one drive, with an uncertainty measured from
// the shots themselves (not from a noise model): the spectra of the first-
// differenced records (as in dsp/fft_ratio) are summed over the shots — the
// coherent average, equal to the FFT ratio of the shot-averaged record — and
// the standard error of ln Z = ln|Z| + j·arg Z per bin comes from the
// delete-one jackknife over the shots. Used by the gap diagnosis to weight
// the misfit so that a gap inside the noise is reported as no gap.
#include <Eigen/Core>
#include <vector>

#include "dsp/divider.hpp"
#include "dsp/impedance_types.hpp"

namespace piezo::dsp {

struct ShotEnsembleOptions {
  DividerPrep prep;                      // prep.max_samples: record length from t = 0 (0: all)
  double fmin_hz = 1e3, fmax_hz = 120e3;  // bins kept
  // Bins are merged into bands of at least this relative width (log-spaced,
  // ~ 60 per decade at 0.04): fewer, less correlated points for the fit.
  double band_relative_width = 0.0;  // 0: every FFT bin
  // The jackknife variance of n shots has only n − 1 degrees of freedom; the
  // noise varies slowly with frequency, so the variances are averaged over
  // ±smooth_points neighbours (≈ (2k+1)(n−1) degrees of freedom). Otherwise
  // χ² weighted by 1/σ̂² would be inflated by (n−1)/(n−3) and heavy-tailed.
  int smooth_points = 4;
  // Model the records' end (dsp/record_tail.hpp): the end level fitted over
  // the last quarter instead of the last sample's noise in every bin, and the
  // decay that continues past the record added back.
  bool tail_correction = true;
  // The drive is linear between samples taken at the DAQ's clock (the bench's
  // AWG, as PronyImpedanceOptions::ramp_onset). Channel 1 then records the
  // generator's samples — the ALIASED spectrum of the continuous drive, X_d —
  // while channel 2 records the response to the continuous drive, whose
  // spectrum is X_d·sinc²(f/fs) (the triangle kernel's transform; the
  // divider's response beyond fs is too small to alias back). The ratio reads
  // T·sinc²(f/fs): |Z| 3.3e-4 low at 100 kHz, 10 MS/s — small, but it is 12σ
  // of a 0.05 %-noise chirp capture. Set: channel 1's spectrum is scaled by
  // sinc² before the ratio.
  bool linear_drive = false;
};

struct ShotEnsemble {
  Eigen::VectorXd f_hz;
  Eigen::VectorXcd z_ohm;
  Eigen::VectorXd sigma_log_mag;  // standard error of ln|Z| (nepers)
  Eigen::VectorXd sigma_phase;    // standard error of arg Z (rad)
  int shots = 0;
  std::size_t samples = 0;  // per shot, from t = 0
};

// Needs ≥ 3 records of equal length, rate and R1 (throws std::invalid_argument
// naming the problem otherwise); clipped records are refused by the prep.
ShotEnsemble impedance_shot_ensemble(const std::vector<DividerRecord>& shots, const ShotEnsembleOptions& opt = {});

}  // namespace piezo::dsp
