#include "dsp/signal_stats.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace piezo::dsp {

namespace {
// Longest run of consecutive samples exactly equal to v.
std::size_t longest_run_at(std::span<const double> x, double v) {
  std::size_t best = 0, cur = 0;
  for (double s : x) {
    cur = (s == v) ? cur + 1 : 0;
    best = std::max(best, cur);
  }
  return best;
}
}  // namespace

SignalStats compute_stats(std::span<const double> x, const ClipDetection& clip) {
  if (x.empty()) throw std::invalid_argument("compute_stats: empty signal");
  SignalStats st;
  auto [mn, mx] = std::minmax_element(x.begin(), x.end());
  st.min = *mn;
  st.max = *mx;
  long double sum = 0.0L, sum2 = 0.0L;
  for (double s : x) {
    sum += s;
    sum2 += static_cast<long double>(s) * s;
  }
  st.mean = static_cast<double>(sum / x.size());
  st.rms = static_cast<double>(std::sqrt(sum2 / x.size()));

  if (clip.range_v && *clip.range_v > 0.0) {
    const double lim = *clip.range_v * (1.0 - clip.rel_margin);
    st.samples_at_limit = static_cast<std::size_t>(
        std::count_if(x.begin(), x.end(), [lim](double s) { return std::fabs(s) >= lim; }));
    st.clipped = st.samples_at_limit > 0;
  } else {
    // A pinned converter sits at the signal's largest magnitude (the range is
    // symmetric); a slow tail sitting on one code at the other extreme (an
    // exp_decay ending near 0 V) is not clipping.
    const double peak = std::max(std::fabs(st.max), std::fabs(st.min));
    const bool hi_is_peak = std::fabs(st.max) >= 0.99 * peak, lo_is_peak = std::fabs(st.min) >= 0.99 * peak;
    const std::size_t run_hi = st.max != 0.0 && hi_is_peak ? longest_run_at(x, st.max) : 0;
    const std::size_t run_lo = st.min != 0.0 && lo_is_peak ? longest_run_at(x, st.min) : 0;
    st.clipped = std::max(run_hi, run_lo) >= clip.min_flat_run;
    if (st.clipped) {
      st.samples_at_limit = static_cast<std::size_t>(std::count_if(
          x.begin(), x.end(), [&](double s) { return s == st.max || s == st.min; }));
    }
  }
  return st;
}

double log_gamma_tail(int w, double x) {
  // ln P(Gamma(w, 1) ≥ x) = ln(e^{-x} Σ_{k<w} x^k/k!)
  double best = -INFINITY;
  std::vector<double> t(static_cast<std::size_t>(std::max(w, 1)));
  for (int k = 0; k < w; ++k) {
    t[static_cast<std::size_t>(k)] = (k == 0 ? 0.0 : k * std::log(std::max(x, 1e-300))) - std::lgamma(k + 1.0);
    best = std::max(best, t[static_cast<std::size_t>(k)]);
  }
  double sum = 0;
  for (int k = 0; k < w; ++k) sum += std::exp(t[static_cast<std::size_t>(k)] - best);
  return -x + best + std::log(sum);
}

}  // namespace piezo::dsp
