#include "dsp/fft.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <map>
#include <mutex>
#include <new>
#include <stdexcept>

#include "dsp/work_counters.hpp"

namespace piezo::dsp {

namespace {
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// The plans of each size, made once and shared by every RealFft of that size
// (issue 43 item 2: a replayed capture built and destroyed about 1000 plans,
// and FFTW recomputed the twiddle factors of each — 8.5 % of its time in
// fftw_mkapiplan). A RealFft executes them on its own buffers (FFTW's
// new-array execute: same size, same fftw_alloc alignment, out of place, so
// the same algorithm and the same numbers). Plans in use are never destroyed;
// of the idle ones the kMaxIdle most recently used are kept, so a batch of
// captures of many lengths holds a bounded set.
constexpr std::size_t kMaxIdle = 16;
struct CachedPlans {
  fftw_plan fwd = nullptr, inv = nullptr;
  int users = 0;
  std::uint64_t last_use = 0;
};
// Destroys the plans at exit (leak checkers see none left).
struct PlanCache : std::map<std::size_t, CachedPlans> {
  PlanCache() = default;
  PlanCache(const PlanCache&) = delete;
  PlanCache& operator=(const PlanCache&) = delete;
  ~PlanCache() {
    for (auto& [n, p] : *this) {
      fftw_destroy_plan(p.fwd);
      fftw_destroy_plan(p.inv);
    }
  }
};
PlanCache& plan_cache() {  // guarded by planner_mutex()
  static PlanCache c;
  return c;
}
std::uint64_t g_tick = 0;  // guarded by planner_mutex()

void evict_idle() {  // planner_mutex() held
  auto& cache = plan_cache();
  for (;;) {
    std::size_t idle = 0;
    auto oldest = cache.end();
    for (auto it = cache.begin(); it != cache.end(); ++it)
      if (it->second.users == 0) {
        ++idle;
        if (oldest == cache.end() || it->second.last_use < oldest->second.last_use) oldest = it;
      }
    if (idle <= kMaxIdle) return;
    fftw_destroy_plan(oldest->second.fwd);
    fftw_destroy_plan(oldest->second.inv);
    cache.erase(oldest);
  }
}
}  // namespace

RealFft::RealFft(std::size_t n) : n_(n) {
  if (n < 2) throw std::invalid_argument("RealFft: size must be >= 2");
  std::lock_guard<std::mutex> lock(planner_mutex());
  rbuf_ = fftw_alloc_real(n);
  auto* c = fftw_alloc_complex(n / 2 + 1);
  cbuf_ = c;
  if (!rbuf_ || !c) {
    fftw_free(rbuf_);
    fftw_free(c);
    throw std::bad_alloc();
  }
  auto& cache = plan_cache();
  auto it = cache.find(n);
  if (it == cache.end()) {
    // FFTW_ESTIMATE does not touch the arrays while planning.
    CachedPlans p;
    p.fwd = fftw_plan_dft_r2c_1d(static_cast<int>(n), rbuf_, c, FFTW_ESTIMATE);
    p.inv = fftw_plan_dft_c2r_1d(static_cast<int>(n), c, rbuf_, FFTW_ESTIMATE);
    if (!p.fwd || !p.inv) {
      if (p.fwd) fftw_destroy_plan(p.fwd);
      if (p.inv) fftw_destroy_plan(p.inv);
      fftw_free(rbuf_);
      fftw_free(c);
      throw std::runtime_error("RealFft: FFTW planning failed");
    }
    it = cache.emplace(n, p).first;
  }
  ++it->second.users;
  fwd_ = it->second.fwd;
  inv_ = it->second.inv;
}

RealFft::~RealFft() {
  std::lock_guard<std::mutex> lock(planner_mutex());
  auto& cache = plan_cache();
  if (auto it = cache.find(n_); it != cache.end()) {
    --it->second.users;
    it->second.last_use = ++g_tick;
  }
  evict_idle();
  fftw_free(rbuf_);
  fftw_free(cbuf_);
}

void RealFft::forward(const double* in, std::size_t count, std::complex<double>* out) {
  g_ffts.fetch_add(1, std::memory_order_relaxed);  // dsp/work_counters.hpp
  count = std::min(count, n_);
  std::memcpy(rbuf_, in, count * sizeof(double));
  std::fill(rbuf_ + count, rbuf_ + n_, 0.0);
  fftw_execute_dft_r2c(static_cast<fftw_plan>(fwd_), rbuf_, static_cast<fftw_complex*>(cbuf_));
  std::memcpy(static_cast<void*>(out), cbuf_, bins() * sizeof(fftw_complex));
}

void RealFft::inverse(const std::complex<double>* in, double* out, std::size_t count) {
  g_ffts.fetch_add(1, std::memory_order_relaxed);
  std::memcpy(cbuf_, static_cast<const void*>(in), bins() * sizeof(fftw_complex));
  // c2r destroys its input: cbuf_ is scratch.
  fftw_execute_dft_c2r(static_cast<fftw_plan>(inv_), static_cast<fftw_complex*>(cbuf_), rbuf_);
  std::memcpy(out, rbuf_, std::min(count, n_) * sizeof(double));
}

std::size_t good_fft_size(std::size_t n) {
  if (n <= 2) return 2;
  for (std::size_t m = n;; ++m) {
    std::size_t r = m;
    for (std::size_t p : {2u, 3u, 5u, 7u})
      while (r % p == 0) r /= p;
    if (r == 1) return m;
  }
}

Eigen::VectorXcd rfft(const Eigen::Ref<const Eigen::VectorXd>& x, std::size_t nfft) {
  if (static_cast<std::size_t>(x.size()) > nfft)
    throw std::invalid_argument("rfft: nfft shorter than the signal");
  RealFft f(nfft);
  Eigen::VectorXd tmp = x;  // contiguous copy
  Eigen::VectorXcd out(static_cast<Eigen::Index>(f.bins()));
  f.forward(tmp.data(), static_cast<std::size_t>(tmp.size()), out.data());
  return out;
}

}  // namespace piezo::dsp
