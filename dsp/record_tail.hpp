#pragma once
// What a finite record leaves out of the spectrum of its first difference.
//
// The estimators take the DFT of the first-differenced record (a drive step
// becomes an impulse, dsp/fft_ratio.hpp). That DFT telescopes: at every bin
//   D(ω_k) = (1 − e^{−jω_k})·V(ω_k) + v[N−1],
// so two things about the record's END enter every bin alike:
//   1. the noise of the single last sample v[N−1] — at low frequencies, where
//      |1 − e^{−jω}| is small, it outweighs the noise of the whole record
//      (|1 − e^{−jω}|·√N = 0.44 at 5 kHz for N = 20 000 at 10 MS/s), and the
//      error of Z it causes is the SAME at every frequency: a smooth level and
//      phase offset that no per-bin σ describes;
//   2. the differences after the record ends: a response still decaying at
//      N (the seed's exp_decay drive is at e^{−6} of its peak after 2 ms)
//      misses Σ_{n≥N} Δv[n] e^{−jω n}.
// Both are fixed by a model of the tail, v[N−1+m] = c·r^m (a decay at the
// drive's late-time rate r, r = 1 for a drive that settles at a level):
// the end level c fitted to the record's last quarter replaces the single
// sample, and the continuation adds c·(r − 1)/(1 − r·e^{−jω}) per bin.
// A record whose tail is no such decay (a burst that rang down, a sine) gets
// c from a straight line over its last N/64 samples when the line fits within
// the noise, else its own last sample, and no continuation.
#include <Eigen/Core>
#include <complex>

namespace piezo::dsp {

struct RecordTail {
  bool decaying = false;  // r was measured (else r = 1, line or last sample)
  double r = 1.0;         // per-sample decay of the tail
};

// The late-time decay of `drive` (the shot-averaged v1): the ratio of the
// sums over the two halves of its last quarter, when the first sum stands
// clear of the noise (> 10σ) and both have one sign; otherwise not decaying.
RecordTail measure_tail(const Eigen::VectorXd& drive);

// Correction to add to bin k (of nfft = v.size()) of the DFT of the
// differenced record v: (c − v[N−1]) + c·(r − 1)/(1 − r·e^{−jω_k}).
class TailCorrection {
 public:
  TailCorrection(const Eigen::VectorXd& v, const RecordTail& tail);
  std::complex<double> at_bin(Eigen::Index k) const;
  double end_level() const { return c_; }

 private:
  double c_ = 0, last_ = 0, r_ = 1;
  Eigen::Index n_ = 0;
};

}  // namespace piezo::dsp
