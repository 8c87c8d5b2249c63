#include "dsp/fft.hpp"

#include <fftw3.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <mutex>
#include <utility>
#include <new>
#include <stdexcept>

#include "dsp/work_counters.hpp"

namespace piezo::dsp {

namespace {
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// The shared r2c and c2r plans of each size, each made on its first use
// (under the planner lock, on that RealFft's buffers: every RealFft's buffers
// come from fftw_alloc, so they have the alignment the plans assume). Kept
// for the process; at most kMaxSharedSizes sizes (a batch of captures of
// many lengths plans the rest per object, as before). FFTW_ESTIMATE chooses
// a plan from the size alone, so a plan made later or elsewhere is the same.
constexpr std::size_t kMaxSharedSizes = 64;
std::map<std::size_t, std::pair<fftw_plan, fftw_plan>>& shared_plans() {
  static auto* plans = new std::map<std::size_t, std::pair<fftw_plan, fftw_plan>>();  // never freed: outlives every RealFft
  return *plans;
}

// The same for ComplexFft's in-place transforms.
std::map<std::size_t, std::pair<fftw_plan, fftw_plan>>& shared_complex_plans() {
  static auto* plans = new std::map<std::size_t, std::pair<fftw_plan, fftw_plan>>();  // never freed
  return *plans;
}

fftw_plan make_plan(std::size_t n, double* r, fftw_complex* c, bool inverse) {
  fftw_plan p = inverse ? fftw_plan_dft_c2r_1d(static_cast<int>(n), c, r, FFTW_ESTIMATE)
                        : fftw_plan_dft_r2c_1d(static_cast<int>(n), r, c, FFTW_ESTIMATE);
  if (!p) throw std::runtime_error("RealFft: FFTW planning failed");
  return p;
}

// The shared plan of size n one way (in `shared`, under the planner lock),
// made by make() if there is none yet; past the size limit make()'s own, and
// `own` set (its object destroys it).
template <class Make>
fftw_plan plan_of(std::map<std::size_t, std::pair<fftw_plan, fftw_plan>>& shared, std::size_t n, bool inverse,
                  bool& own, Make make) {
  auto it = shared.find(n);
  if (it == shared.end() && shared.size() < kMaxSharedSizes)
    it = shared.emplace(n, std::pair<fftw_plan, fftw_plan>{nullptr, nullptr}).first;
  fftw_plan* slot = it == shared.end() ? nullptr : inverse ? &it->second.second : &it->second.first;
  if (slot && *slot) return *slot;
  const fftw_plan p = make();
  if (slot)
    *slot = p;
  else
    own = true;
  return p;
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
  // The shared plans made so far; the others on first use (plan()): a size
  // only ever transformed forward (a record's spectrum) is never planned
  // backward — planning a long transform costs more than running it.
  if (auto it = shared_plans().find(n); it != shared_plans().end()) {
    fwd_ = it->second.first;
    inv_ = it->second.second;
  }
}

void* RealFft::plan(bool inverse) {
  std::lock_guard<std::mutex> lock(planner_mutex());
  // Planned on this object's buffers (FFTW_ESTIMATE does not touch them);
  // the plans never read them again (new-array execute only).
  return (inverse ? inv_ : fwd_) = plan_of(shared_plans(), n_, inverse, inverse ? own_inv_ : own_fwd_, [&] {
           return make_plan(n_, rbuf_, static_cast<fftw_complex*>(cbuf_), inverse);
         });
}

RealFft::~RealFft() {
  std::lock_guard<std::mutex> lock(planner_mutex());
  if (own_fwd_) fftw_destroy_plan(static_cast<fftw_plan>(fwd_));
  if (own_inv_) fftw_destroy_plan(static_cast<fftw_plan>(inv_));
  fftw_free(rbuf_);
  fftw_free(cbuf_);
}

void RealFft::forward(const double* in, std::size_t count, std::complex<double>* out) {
  g_ffts.fetch_add(1, std::memory_order_relaxed);  // dsp/work_counters.hpp
  if (!fwd_) plan(false);
  count = std::min(count, n_);
  std::memcpy(rbuf_, in, count * sizeof(double));
  std::fill(rbuf_ + count, rbuf_ + n_, 0.0);
  fftw_execute_dft_r2c(static_cast<fftw_plan>(fwd_), rbuf_, static_cast<fftw_complex*>(cbuf_));
  std::memcpy(static_cast<void*>(out), cbuf_, bins() * sizeof(fftw_complex));
}

void RealFft::inverse(const std::complex<double>* in, double* out, std::size_t count) {
  g_ffts.fetch_add(1, std::memory_order_relaxed);
  if (!inv_) plan(true);
  std::memcpy(cbuf_, static_cast<const void*>(in), bins() * sizeof(fftw_complex));
  // c2r destroys its input: cbuf_ is scratch
  fftw_execute_dft_c2r(static_cast<fftw_plan>(inv_), static_cast<fftw_complex*>(cbuf_), rbuf_);
  std::memcpy(out, rbuf_, std::min(count, n_) * sizeof(double));
}

ComplexFft::ComplexFft(std::size_t n) : n_(n) {
  if (n < 1) throw std::invalid_argument("ComplexFft: size must be >= 1");
  std::lock_guard<std::mutex> lock(planner_mutex());
  auto* c = fftw_alloc_complex(n);
  if (!c) throw std::bad_alloc();
  buf_ = reinterpret_cast<std::complex<double>*>(c);  // the layouts agree (FFTW's manual, §4.1.1)
}

void* ComplexFft::plan(bool inverse) {
  // Shared as RealFft's (in place, on the first object's buffer: every
  // buffer comes from fftw_alloc), each direction on first use.
  std::lock_guard<std::mutex> lock(planner_mutex());
  return (inverse ? inv_ : fwd_) = plan_of(shared_complex_plans(), n_, inverse, inverse ? own_inv_ : own_fwd_, [&] {
           auto* c = reinterpret_cast<fftw_complex*>(buf_);
           const fftw_plan p =
               fftw_plan_dft_1d(static_cast<int>(n_), c, c, inverse ? FFTW_BACKWARD : FFTW_FORWARD, FFTW_ESTIMATE);
           if (!p) throw std::runtime_error("ComplexFft: FFTW planning failed");
           return p;
         });
}

ComplexFft::~ComplexFft() {
  std::lock_guard<std::mutex> lock(planner_mutex());
  if (own_fwd_) fftw_destroy_plan(static_cast<fftw_plan>(fwd_));
  if (own_inv_) fftw_destroy_plan(static_cast<fftw_plan>(inv_));
  fftw_free(buf_);
}

void ComplexFft::forward() {
  if (!fwd_) plan(false);
  auto* c = reinterpret_cast<fftw_complex*>(buf_);
  fftw_execute_dft(static_cast<fftw_plan>(fwd_), c, c);
}

void ComplexFft::inverse() {
  if (!inv_) plan(true);
  auto* c = reinterpret_cast<fftw_complex*>(buf_);
  fftw_execute_dft(static_cast<fftw_plan>(inv_), c, c);
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
