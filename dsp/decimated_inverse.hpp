#pragma once
// Every d-th sample of a band-limited inverse real DFT, by Bluestein's chirp-z
// transform (Rabiner, Schafer & Rader 1969): the samples x[d·m], m < count, of
//   x[t] = Σ_{k=0}^{N−1} X[k] e^{+j2πkt/N}   (unnormalised, as RealFft::inverse)
// for a one-sided spectrum X[0..N/2] that is zero above bin k_max. The output
// error's residual (update/output_error) keeps every d-th sample of a record
// padded to N = 4n: its spectrum has k_max ≈ 1.25·N/d bins, and the samples it
// keeps are n/d, so two complex FFTs of about k_max + n/d points replace a real
// one of N (≈ 5 times fewer operations on the corpus's records). Exact up to
// rounding: tests/dsp/test_decimated_inverse.cpp checks it against RealFft and
// the direct sum.
#include <complex>
#include <cstddef>
#include <vector>

#include "dsp/fft.hpp"

namespace piezo::dsp {

class DecimatedInverse {
 public:
  DecimatedInverse(std::size_t n, std::size_t k_max, std::size_t d, std::size_t count);
  DecimatedInverse(const DecimatedInverse& o);  // its own FFT buffer (one per thread)
  DecimatedInverse& operator=(const DecimatedInverse&) = delete;

  std::size_t size() const { return n_; }
  std::size_t count() const { return count_; }
  // bins: X[0..k_max] (imaginary parts of X[0] and X[N/2] ignored, as FFTW's
  // c2r does); out: count samples x[0], x[d], x[2d], …
  void operator()(const std::complex<double>* bins, double* out);

 private:
  std::size_t n_, k_max_, count_;
  std::vector<std::complex<double>> chirp_;   // c(j) = e^{jπ d j²/N}, j ≤ max(k_max, count)
  std::vector<std::complex<double>> kernel_;  // FFT of conj c(j), j = −k_max … count−1, / L
  ComplexFft fft_;                            // length L ≥ k_max + count
};

}  // namespace piezo::dsp
