#pragma once
// Thin RAII wrapper over FFTW3's real transforms (the only FFTW user in dsp/).
// Plans are made with FFTW_ESTIMATE under a process-wide lock (the FFTW planner
// is not thread-safe); execution is lock-free, one RealFft per thread.
// RealFft's plans are made once per size and process and shared (FFTW's
// new-array execute: each RealFft transforms its own buffers with them):
// planning, even FFTW_ESTIMATE's, cost twice the transforms themselves in a
// replay, where every fit's Problem and each of its scan forks made its own
// (issue 43). The transforms are the same plans', so bit-identical.
#include <Eigen/Core>
#include <complex>
#include <cstddef>

namespace piezo::dsp {

class RealFft {
 public:
  explicit RealFft(std::size_t n);
  ~RealFft();
  RealFft(const RealFft&) = delete;
  RealFft& operator=(const RealFft&) = delete;

  std::size_t size() const { return n_; }
  std::size_t bins() const { return n_ / 2 + 1; }
  // X[k] = Σ x[n] e^{−j2πkn/N}; `in` holds `count` ≤ N samples, the rest is zero.
  void forward(const double* in, std::size_t count, std::complex<double>* out);
  // x[n] = Σ X[k] e^{+j2πkn/N} (unnormalised: divide by N), first `count` samples.
  void inverse(const std::complex<double>* in, double* out, std::size_t count);

 private:
  std::size_t n_;
  double* rbuf_ = nullptr;
  void* cbuf_ = nullptr;
  void* fwd_ = nullptr;  // null until the first transform that way (plan())
  void* inv_ = nullptr;
  bool own_fwd_ = false, own_inv_ = false;  // past the shared cache's size limit: its own plans
  void* plan(bool inverse);  // fwd_ or inv_: the shared plan of this size, made if need be
};

// FFTW3's complex transform of size n, in place on its own buffer (data()).
class ComplexFft {
 public:
  explicit ComplexFft(std::size_t n);
  ~ComplexFft();
  ComplexFft(const ComplexFft&) = delete;
  ComplexFft& operator=(const ComplexFft&) = delete;

  std::size_t size() const { return n_; }
  std::complex<double>* data() { return buf_; }
  void forward();  // X[k] = Σ x[n] e^{−j2πkn/N}
  void inverse();  // x[n] = Σ X[k] e^{+j2πkn/N} (unnormalised)

 private:
  std::size_t n_;
  std::complex<double>* buf_ = nullptr;
  void* fwd_ = nullptr;  // null until the first transform that way (plan())
  void* inv_ = nullptr;
  bool own_fwd_ = false, own_inv_ = false;  // past the shared cache's size limit: its own plans
  void* plan(bool inverse);
};

// Smallest n' >= n whose prime factors are 2, 3, 5, 7 (fast FFTW sizes).
std::size_t good_fft_size(std::size_t n);

// One-sided spectrum of x zero-padded to nfft (nfft/2 + 1 bins).
Eigen::VectorXcd rfft(const Eigen::Ref<const Eigen::VectorXd>& x, std::size_t nfft);

}  // namespace piezo::dsp
