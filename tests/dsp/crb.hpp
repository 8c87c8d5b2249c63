#pragma once
// Cramér–Rao bound of a pole frequency for the multi-channel damped-exponential
// model the Prony-SS fit uses (shared poles, free complex residues per channel,
// independent white Gaussian noise of std sigma[c] on channel c).
#include <complex>
#include <vector>

namespace piezo::crb {

struct Channel {
  std::vector<std::complex<double>> residue;  // one per pole of `poles` (0 allowed)
  double sigma = 0;                           // noise std
};

// poles: real poles and one representative (Im > 0) per conjugate pair; the
// residues of a pair's conjugate are the conjugates. Returns the CRB standard
// deviation in Hz of Im(poles[index])/2π from samples k = 0..n−1 at fs.
double pole_frequency_crb_hz(const std::vector<std::complex<double>>& poles,
                             const std::vector<Channel>& channels, double fs, std::size_t n,
                             std::size_t index);

}  // namespace piezo::crb
