// Shot averaging and the pretrigger's offset removal (shot_average.hpp).
#include "update/output_error/shot_average.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <exception>
#include <span>
#include <cmath>
#include <complex>
#include <utility>

#include "dsp/deskew.hpp"
#include "dsp/fft.hpp"
#include "update/output_error/common.hpp"

namespace piezo::update::oe {

namespace {

// Delay of vk against v0 (samples, > 0: vk late) from the drive's onset: the
// integer lag of the cross-correlation (dsp::xcorr_delay), then the weighted
// least-squares phase slope of the first differences' cross-spectrum below
// an eighth of the sample rate (where the onset's pulse, not the
// differences' amplified noise, is) and above the noise. Only the 512 samples from 64 before the
// onset: the rest of the record adds noise and no timing. A jump's sub-sample
// position is not in its samples: a step drive's jitter comes out to the
// sample; a drive that ramps from idle over a sample or more (the simulated
// AWG's, a real AWG's reconstruction) gives it to a few hundredths.
double shot_delay_samples(std::span<const double> v0, std::span<const double> vk, std::size_t onset) {
  const std::size_t n = v0.size();
  const std::size_t lo = onset > 64 ? onset - 64 : 0;
  const std::size_t w = std::min<std::size_t>(n - lo, 512);
  if (w < 32) return 0.0;
  const auto a = v0.subspan(lo, w), b = vk.subspan(lo, w);
  const double m0 = std::round(dsp::xcorr_delay(a, b, 1.0, 16.0));
  std::vector<double> d0(w, 0.0), dk(w, 0.0);
  for (std::size_t i = 1; i < w; ++i) {
    d0[i] = a[i] - a[i - 1];
    dk[i] = b[i] - b[i - 1];
  }
  const std::size_t nfft = dsp::good_fft_size(2 * w);
  dsp::RealFft fft(nfft);
  std::vector<cd> x0(fft.bins()), xk(fft.bins());
  fft.forward(d0.data(), w, x0.data());
  fft.forward(dk.data(), w, xk.data());
  // The bins where the onset stands above the noise: |X0·Xk| beyond 10× its
  // noise, w·σ0·σk with σ the differences' std before the onset (the
  // pretrigger's 64 samples); without a pretrigger, 10× the median of the
  // upper half of the band (noise there for a drive that rises over more
  // than a sample).
  double floor = 0;
  if (onset >= 64) {
    auto sd = [&](const std::vector<double>& d) {
      double m = 0, q = 0;
      for (std::size_t i = 1; i < 64; ++i) m += d[i];
      m /= 63.0;
      for (std::size_t i = 1; i < 64; ++i) q += (d[i] - m) * (d[i] - m);
      return std::sqrt(q / 62.0);
    };
    floor = 10.0 * double(w) * sd(d0) * sd(dk);
  } else {
    std::vector<double> hi;
    for (std::size_t j = nfft / 4; j < fft.bins(); ++j) hi.push_back(std::abs(x0[j] * xk[j]));
    std::nth_element(hi.begin(), hi.begin() + static_cast<long>(hi.size() / 2), hi.end());
    floor = hi.empty() ? 0.0 : 10.0 * hi[hi.size() / 2];
  }
  double num = 0, den = 0;
  for (std::size_t j = 1; j <= nfft / 8; ++j) {
    const double om = kTwoPi * double(j) / double(nfft);
    const cd c = std::conj(x0[j]) * xk[j] * std::polar(1.0, om * m0);
    if (!(std::abs(c) > floor)) continue;
    num += std::abs(c) * om * std::arg(c);
    den += std::abs(c) * om * om;
  }
  return den > 0 ? m0 - num / den : m0;
}

}  // namespace

Averaged average(const OeData& d) {
  if (d.shots.empty()) fail("no shots");
  // Group by (length, pretrigger): the largest group.
  std::size_t best = 0, best_count = 0;
  for (std::size_t i = 0; i < d.shots.size(); ++i) {
    std::size_t c = 0;
    for (const auto& s : d.shots)
      c += s.v1.size() == d.shots[i].v1.size() && s.pretrigger == d.shots[i].pretrigger;
    if (c > best_count) best = i, best_count = c;
  }
  const OeShot& ref = d.shots[best];
  const std::size_t n = ref.v1.size();
  Averaged a;
  a.v1.assign(n, 0.0);
  a.v2.assign(n, 0.0);
  a.pretrigger = ref.pretrigger;
  std::vector<const OeShot*> used;
  for (const auto& s : d.shots) {
    if (s.v1.size() != n || s.pretrigger != ref.pretrigger) continue;
    if (s.v2.size() != n) fail("a shot's v1 and v2 differ in length");
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(s.v1[i]) || !std::isfinite(s.v2[i])) fail("a shot holds NaN or Inf samples");
    used.push_back(&s);
  }
  // Trigger jitter: each shot's delay against the first, from the
  // cross-correlation of the drives' records (dsp::xcorr_delay, below a
  // sample by interpolation). Shots are aligned on the first (both channels,
  // dsp::deskew_channel: the drive's jump kept on its sample) when any is off
  // by more than kJitterSamples — averaging them unaligned would smear the
  // record's high frequencies.
  a.jitter_samples.assign(used.size(), 0.0);
  std::vector<std::vector<double>> shifted1(used.size()), shifted2(used.size());
  if (used.size() >= 2 && d.sample_rate_hz > 0 && ref.pretrigger > 0) {
    double worst = 0;
    for (std::size_t k = 1; k < used.size(); ++k) {
      try {
        a.jitter_samples[k] = shot_delay_samples(used[0]->v1, used[k]->v1, ref.pretrigger);
      } catch (const std::exception&) {
        a.jitter_samples[k] = 0.0;
      }
      if (!std::isfinite(a.jitter_samples[k])) a.jitter_samples[k] = 0.0;
      worst = std::max(worst, std::abs(a.jitter_samples[k]));
    }
    a.aligned = worst > kJitterSamples;
    if (a.aligned)
      for (std::size_t k = 1; k < used.size(); ++k) {
        const double delay = a.jitter_samples[k] / d.sample_rate_hz;
        shifted1[k] = dsp::deskew_channel(used[k]->v1, d.sample_rate_hz, ref.pretrigger, delay);
        shifted2[k] = dsp::deskew_channel(used[k]->v2, d.sample_rate_hz, ref.pretrigger, delay);
      }
  }
  auto ch1 = [&](std::size_t k) -> std::span<const double> {
    return shifted1[k].empty() ? used[k]->v1 : std::span<const double>(shifted1[k]);
  };
  auto ch2 = [&](std::size_t k) -> std::span<const double> {
    return shifted2[k].empty() ? used[k]->v2 : std::span<const double>(shifted2[k]);
  };
  for (std::size_t k = 0; k < used.size(); ++k) {
    const auto x1 = ch1(k), x2 = ch2(k);
    for (std::size_t i = 0; i < n; ++i) {
      a.v1[i] += x1[i];
      a.v2[i] += x2[i];
    }
  }
  a.shots = static_cast<int>(used.size());
  for (const OeShot* s : used) a.index.push_back(static_cast<int>(s - d.shots.data()));
  for (auto& v : a.v1) v /= a.shots;
  for (auto& v : a.v2) v /= a.shots;
  if (a.shots >= 2)
    for (std::size_t k = 0; k < used.size(); ++k) {
      const auto x1 = ch1(k), x2 = ch2(k);
      std::vector<double> d1(n), d2(n);
      for (std::size_t i = 0; i < n; ++i) {
        d1[i] = x1[i] - a.v1[i];
        d2[i] = x2[i] - a.v2[i];
      }
      a.dev1.push_back(std::move(d1));
      a.dev2.push_back(std::move(d2));
    }
  // DAQ offsets: the idle level before the drive (with a pretrigger of its own).
  if (a.pretrigger >= 16 && a.pretrigger < n) {
    double m1 = 0, m2 = 0;
    for (std::size_t i = 0; i < a.pretrigger; ++i) {
      m1 += a.v1[i];
      m2 += a.v2[i];
    }
    m1 /= double(a.pretrigger);
    m2 /= double(a.pretrigger);
    for (std::size_t i = 0; i < n; ++i) {
      a.v1[i] -= m1;
      a.v2[i] -= m2;
    }
    double s1 = 0, s2 = 0;
    for (std::size_t i = 0; i < a.pretrigger; ++i) {
      s1 += a.v1[i] * a.v1[i];
      s2 += a.v2[i] * a.v2[i];
    }
    const double p = double(a.pretrigger);
    a.with_offsets = true;
    a.offset_v[0] = m1;
    a.offset_v[1] = m2;
    a.offset_sigma_v[0] = std::sqrt(s1 / (p - 1.0) / p);
    a.offset_sigma_v[1] = std::sqrt(s2 / (p - 1.0) / p);
  }
  return a;
}

}  // namespace piezo::update::oe
