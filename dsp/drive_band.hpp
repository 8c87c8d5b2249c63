#pragma once
// The band a recorded drive covers (issue 40): the frequencies where the
// recorded channel 1 (the generator's side of R1) stands clearly above its own
// white-noise floor. A feature of the impedance outside it was estimated from
// noise, not from the drive's response, and is not used by the model update.
//   P_k  = |X_k|², X the DFT of the record (offset removed), smoothed over a
//          third of an octave around bin k (mean of the bins in [k/2^(1/6), k·2^(1/6)]);
//   noise floor per bin  N·σ²  (σ: dsp::estimate_noise_std of the record);
//   SNR_k = sqrt(max(0, P_k − N·σ²) / (N·σ²)); the band is [lowest, highest]
//          bin with SNR_k ≥ min_snr.
#include <span>
#include <string>

namespace piezo::dsp {

struct DriveBand {
  bool found = false;  // at least one bin above the threshold
  double lo_hz = 0, hi_hz = 0;
  double noise_std = 0;  // σ of the record's white noise (volts)
  double min_snr = 0;
  std::string note;  // how it was found, in words
};

// `x`: channel 1 of the record (or the average of several shots' records),
// `pretrigger`: samples before t = 0 (their mean is removed when ≥ 16).
// Throws std::invalid_argument for fewer than 64 samples or fs ≤ 0.
DriveBand drive_band(std::span<const double> x, double fs_hz, std::size_t pretrigger = 0, double min_snr = 3.0);

}  // namespace piezo::dsp
