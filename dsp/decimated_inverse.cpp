// Bluestein's chirp-z evaluation of a decimated inverse real DFT
// (decimated_inverse.hpp). With w = e^{j2πd/N}, the samples are
//   x[dm] = 2 Re S[m],   S[m] = Σ_{k=0}^{K} a_k w^{km},
// a_0 = Re X[0]/2, a_{N/2} = Re X[N/2]/2 (N even and K = N/2), a_k = X[k]
// otherwise; and km = (k² + m² − (m−k)²)/2 turns S into a convolution:
//   S[m] = c(m) Σ_k [a_k c(k)] conj c(m−k),   c(j) = w^{j²/2} = e^{jπdj²/N}.
#include "dsp/decimated_inverse.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <stdexcept>
#include <string>

#include "dsp/work_counters.hpp"
#include "numerics/simd_clones.hpp"

namespace piezo::dsp {

namespace {

// e^{jπ d j²/N}, its phase reduced exactly in integers (d j² mod 2N) first.
std::complex<double> chirp(std::size_t j, std::size_t d, std::size_t n) {
  const unsigned __int128 two_n = 2 * static_cast<unsigned __int128>(n);
  const auto r = static_cast<std::uint64_t>((static_cast<unsigned __int128>(j) * j % two_n) * d % two_n);
  const double phase = std::numbers::pi * static_cast<double>(r) / static_cast<double>(n);
  return {std::cos(phase), std::sin(phase)};
}

std::size_t convolution_length(std::size_t k_max, std::size_t count) {
  return good_fft_size(std::max<std::size_t>(2, k_max + count));
}

}  // namespace

DecimatedInverse::DecimatedInverse(std::size_t n, std::size_t k_max, std::size_t d, std::size_t count)
    : n_(n), k_max_(k_max), count_(count), fft_(convolution_length(k_max, count)) {
  if (n < 2 || d < 1 || count < 1 || k_max > n / 2)
    throw std::invalid_argument("DecimatedInverse: needs N >= 2, d >= 1, count >= 1 and k_max <= N/2 (N " +
                                std::to_string(n) + ", k_max " + std::to_string(k_max) + ", d " +
                                std::to_string(d) + ", count " + std::to_string(count) + ")");
  const std::size_t l = fft_.size();
  chirp_.resize(std::max(k_max, count - 1) + 1);
  for (std::size_t j = 0; j < chirp_.size(); ++j) chirp_[j] = chirp(j, d, n);
  // conj c(j) at lags j = 0 … count−1 and, wrapped to the end, j = −1 … −k_max.
  std::complex<double>* v = fft_.data();
  std::fill(v, v + l, std::complex<double>(0.0, 0.0));
  for (std::size_t j = 0; j < count; ++j) v[j] = std::conj(chirp_[j]);
  for (std::size_t j = 1; j <= k_max; ++j) v[l - j] = std::conj(chirp_[j]);
  fft_.forward();
  kernel_.assign(v, v + l);
  for (auto& z : kernel_) z /= static_cast<double>(l);  // the inverse FFT's 1/L, once
}

DecimatedInverse::DecimatedInverse(const DecimatedInverse& o)
    : n_(o.n_), k_max_(o.k_max_), count_(o.count_), chirp_(o.chirp_), kernel_(o.kernel_),
      fft_(o.fft_.size()) {}

namespace {
// The element-wise products of operator(), over the complex arrays' (re, im)
// pairs: (a + jb)(c + jd) = (ac − bd) + j(ad + bc), as std::complex's
// product for finite parts, without its NaN check (a branch per element
// that keeps the loop scalar); in SIMD clones (numerics/simd_clones.hpp).
PIEZO_SIMD_CLONES void multiply(const double* __restrict x, const double* __restrict y, double* __restrict z,
                                std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const double a = x[2 * i], b = x[2 * i + 1], c = y[2 * i], d = y[2 * i + 1];
    z[2 * i] = a * c - b * d;
    z[2 * i + 1] = a * d + b * c;
  }
}
PIEZO_SIMD_CLONES void multiply_in_place(double* __restrict z, const double* __restrict y, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    const double a = z[2 * i], b = z[2 * i + 1], c = y[2 * i], d = y[2 * i + 1];
    z[2 * i] = a * c - b * d;
    z[2 * i + 1] = a * d + b * c;
  }
}
PIEZO_SIMD_CLONES void twice_real_of_product(const double* __restrict x, const double* __restrict y,
                                             double* __restrict out, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) out[i] = 2.0 * (x[2 * i] * y[2 * i] - x[2 * i + 1] * y[2 * i + 1]);
}
const double* parts(const std::complex<double>* z) { return reinterpret_cast<const double*>(z); }
double* parts(std::complex<double>* z) { return reinterpret_cast<double*>(z); }
}  // namespace

void DecimatedInverse::operator()(const std::complex<double>* bins, double* out) {
  g_ffts.fetch_add(1, std::memory_order_relaxed);  // one inverse DFT (dsp/work_counters.hpp)
  const std::size_t l = fft_.size();
  std::complex<double>* u = fft_.data();
  // (std::complex<double> is an array of its two parts: [complex.numbers.general])
  multiply(parts(bins), parts(chirp_.data()), parts(u), k_max_ + 1);
  u[0] = 0.5 * bins[0].real() * chirp_[0];  // a_0 = Re X[0]/2 (chirp_[0] = 1)
  if (2 * k_max_ == n_) u[k_max_] = 0.5 * bins[k_max_].real() * chirp_[k_max_];  // a_{N/2}
  std::fill(u + k_max_ + 1, u + l, std::complex<double>(0.0, 0.0));
  fft_.forward();
  multiply_in_place(parts(u), parts(kernel_.data()), l);
  fft_.inverse();
  twice_real_of_product(parts(chirp_.data()), parts(u), out, count_);
}

}  // namespace piezo::dsp
